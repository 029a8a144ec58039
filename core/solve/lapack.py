"""Cholesky, triangular solves and rank-k updates from the OpenBLAS that numpy bundles, through ctypes.

numpy has no triangular solve and no Cholesky update, and Blender ships numpy without scipy; but every numpy wheel
for Linux and Windows (and the Intel macOS ones) bundles OpenBLAS with LAPACK and CBLAS exported. The block
factorisations of :mod:`.dissection` and :mod:`.linalg` use four of its routines — ``potrf`` (Cholesky), ``trsm``
and ``trsv`` (triangular solves) and ``syrk`` (``C − WᵀW``) — which need about a third of the flops of the
per-block inverse and products of the numpy code (≈ 2.3 s³ instead of ≈ 6.7 s³ per block of s unknowns).

Two naming schemes are found: numpy 1.x's ``numpy.libs/libopenblas64_*`` (symbols ``cblas_dtrsm64_``,
``dpotrf_64_``) and numpy 2.x's ``numpy.libs/libscipy_openblas64_*`` (``scipy_cblas_dtrsm64_``, …). The ``64_``
suffix means 64-bit integer arguments (ILP64); a build without it gets 32-bit ones. The library loaded is the one
numpy already loaded (same file, same handle), so its thread count is numpy's.

Where no library or one of the routines is missing (a numpy on Accelerate or a system BLAS, as Blender may ship),
:func:`routines` returns ``None`` and the callers keep their numpy code. :data:`ENABLED` (or :func:`disabled`)
forces that fallback, so the tests run both.

Arrays are numpy's row-major ``float64``, C-contiguous or a block of rows and columns of such an array (the leading
dimension is read from the strides); the wrappers call CBLAS in row-major order and the Fortran
``dpotrf`` on the transpose (a symmetric matrix is its own transpose: its lower factor in column-major order is the
upper factor ``U``, ``S = Uᵀ U``, in row-major order). The variants are the fastest of OpenBLAS 0.3.23 on blocks of
~166 (measured one thread: ``dpotrf`` "L" 90–115 µs vs "U" 170–195 µs; ``trsm`` left/upper/transposed 200 µs vs
230–450 µs for the others).
"""

from __future__ import annotations

import contextlib
import ctypes
import glob
import os
from collections.abc import Iterator

import numpy as np

ENABLED = True
"""Use the OpenBLAS routines when found; ``False`` makes :func:`routines` return ``None`` (the numpy fallback)."""

_ROW_MAJOR, _NO_TRANS, _TRANS, _UPPER, _NON_UNIT, _LEFT = 101, 111, 112, 121, 131, 141
"""CBLAS enumeration values (``CblasRowMajor``, ``CblasNoTrans``, ``CblasTrans``, ``CblasUpper``, …)."""

_PREFIXES = ("scipy_", "")
_SUFFIXES = ("64_", "")

_FOUND: list = []
"""Cache of :func:`openblas`: empty until searched, then ``[OpenBLAS | None]``."""


class OpenBLAS:
    """The routines of one loaded OpenBLAS; ``has_lapack`` is false when only the thread control was found."""

    def __init__(self, lib: ctypes.CDLL, path: str, prefix: str, suffix: str):
        self.path = path
        self.get_threads = getattr(lib, f"{prefix}openblas_get_num_threads{suffix}")
        self.set_threads = getattr(lib, f"{prefix}openblas_set_num_threads{suffix}")
        self.set_threads.argtypes = [ctypes.c_int]
        self.get_threads.restype = ctypes.c_int
        integer = ctypes.c_int64 if suffix.startswith("64") else ctypes.c_int32
        self._int = integer
        enum, ptr, dbl = ctypes.c_int, ctypes.c_void_p, ctypes.c_double
        names = {
            "potrf": f"{prefix}dpotrf_{suffix}",
            "trsm": f"{prefix}cblas_dtrsm{suffix}",
            "syrk": f"{prefix}cblas_dsyrk{suffix}",
            "trsv": f"{prefix}cblas_dtrsv{suffix}",
        }
        found = {key: getattr(lib, name, None) for key, name in names.items()}
        self.has_lapack = all(f is not None for f in found.values())
        if not self.has_lapack:
            return
        self._potrf = found["potrf"]
        # Fortran: (uplo, n, a, lda, info, hidden length of uplo); every argument by reference
        self._potrf.argtypes = [ctypes.c_char_p, ptr, ptr, ptr, ptr, ctypes.c_size_t]
        self._potrf.restype = None
        self._trsm = found["trsm"]
        self._trsm.argtypes = [enum, enum, enum, enum, enum, integer, integer, dbl, ptr, integer, ptr, integer]
        self._trsm.restype = None
        self._syrk = found["syrk"]
        self._syrk.argtypes = [enum, enum, enum, integer, integer, dbl, ptr, integer, dbl, ptr, integer]
        self._syrk.restype = None
        self._trsv = found["trsv"]
        self._trsv.argtypes = [enum, enum, enum, enum, integer, ptr, integer, ptr, integer]
        self._trsv.restype = None

    def cholesky(self, a: np.ndarray) -> bool:
        """In place: the upper triangle of the symmetric ``a`` (only it is read) becomes ``U`` with ``a = Uᵀ U``.

        Returns ``False`` when ``a`` is not positive definite (LAPACK ``info > 0``; ``a`` is then partly
        overwritten). The strict lower triangle is left as it was.
        """
        lda = _check(a, 2)
        n = a.shape[0]
        if a.shape[1] != n:
            raise ValueError(f"cholesky of a non-square {a.shape} matrix")
        size, ld, info = self._int(n), self._int(lda), self._int(0)
        # the column-major view of the row-major array is its transpose: LAPACK's lower factor L there is U = Lᵀ
        # here (OpenBLAS's "L" variant is about twice as fast as its "U" on blocks of ~160)
        self._potrf(b"L", ctypes.byref(size), a.ctypes.data, ctypes.byref(ld), ctypes.byref(info), 1)
        if info.value < 0:
            raise ValueError(f"dpotrf: illegal argument {-info.value}")
        return info.value == 0

    def solve_upper_transposed(self, U: np.ndarray, b: np.ndarray) -> None:
        """In place ``b ← U⁻ᵀ b`` for the upper triangle ``U`` (n, n) and ``b`` (n, m) (``trsm``)."""
        ldu, ldb = _check(U, 2), _check(b, 2)
        n, m = b.shape
        if U.shape != (n, n):
            raise ValueError(f"triangular solve with {U.shape} and {b.shape}")
        self._trsm(_ROW_MAJOR, _LEFT, _UPPER, _TRANS, _NON_UNIT, n, m, 1.0, U.ctypes.data, ldu, b.ctypes.data, ldb)

    def subtract_gram(self, c: np.ndarray, w: np.ndarray) -> None:
        """In place ``c ← c − wᵀ w`` on the upper triangle of ``c`` (m, m) for ``w`` (n, m) (``syrk``).

        The strict lower triangle of ``c`` is not updated.
        """
        ldc, ldw = _check(c, 2), _check(w, 2)
        n, m = w.shape
        if c.shape != (m, m):
            raise ValueError(f"rank update of {c.shape} by {w.shape}")
        self._syrk(_ROW_MAJOR, _UPPER, _TRANS, m, n, -1.0, w.ctypes.data, ldw, 1.0, c.ctypes.data, ldc)

    def solve_upper_vector(self, U: np.ndarray, x: np.ndarray, transpose: bool = False) -> None:
        """In place ``x ← U⁻¹ x`` (or ``U⁻ᵀ x``) for the upper triangle ``U`` (n, n) and a vector ``x`` (``trsv``)."""
        ldu = _check(U, 2)
        _check(x, 1)
        n = x.shape[0]
        if U.shape != (n, n):
            raise ValueError(f"triangular solve with {U.shape} and {x.shape}")
        trans = _TRANS if transpose else _NO_TRANS
        self._trsv(_ROW_MAJOR, _UPPER, trans, _NON_UNIT, n, U.ctypes.data, ldu, x.ctypes.data, 1)


def _check(a: np.ndarray, ndim: int) -> int:
    """Raise unless ``a`` is ``float64`` with ``ndim`` dimensions whose rows are contiguous (a C-contiguous array,
    or a block of rows and columns of one: ``a[i:j, k:l]``); returns its leading dimension (row stride in
    elements), what BLAS calls ``lda``."""
    if a.dtype != np.float64 or a.ndim != ndim:
        raise ValueError(f"expected a float64 array of {ndim} dimensions, got {a.dtype} {a.shape}")
    if ndim == 1 or a.shape[0] <= 1:
        if not a.flags.c_contiguous:
            raise ValueError(f"expected a contiguous array, got strides {a.strides}")
        return max(a.shape[-1], 1)
    item = a.itemsize
    row, col = a.strides
    if (col != item and a.shape[1] > 1) or row % item or row < item * max(a.shape[1], 1):
        raise ValueError(f"expected rows of contiguous float64, got shape {a.shape} strides {a.strides}")
    return row // item


def _candidates() -> list[str]:
    """Files that can be numpy's bundled OpenBLAS: ``numpy.libs`` (Linux, Windows), ``numpy/.libs`` (older
    wheels), ``numpy/.dylibs`` (macOS)."""
    here = os.path.dirname(np.__file__)
    base = os.path.dirname(here)
    out: list[str] = []
    for folder in (os.path.join(base, "numpy.libs"), os.path.join(here, ".libs"), os.path.join(here, ".dylibs")):
        out += sorted(glob.glob(os.path.join(folder, "*openblas*")))
    return out


def openblas() -> OpenBLAS | None:
    """numpy's bundled OpenBLAS (searched once), or ``None`` if none is found; whatever :data:`ENABLED` says."""
    if not _FOUND:
        _FOUND.append(_search())
    return _FOUND[0]


def _search() -> OpenBLAS | None:
    fallback = None
    for path in _candidates():
        try:
            lib = ctypes.CDLL(path)
        except OSError:
            continue
        for prefix in _PREFIXES:
            for suffix in _SUFFIXES:
                if getattr(lib, f"{prefix}openblas_set_num_threads{suffix}", None) is None:
                    continue
                if getattr(lib, f"{prefix}openblas_get_num_threads{suffix}", None) is None:
                    continue
                found = OpenBLAS(lib, path, prefix, suffix)
                if found.has_lapack:
                    return found
                fallback = fallback or found
    return fallback


def routines() -> OpenBLAS | None:
    """The OpenBLAS whose LAPACK/CBLAS routines the factorisation uses, or ``None`` (numpy fallback): none found,
    a routine missing, or :data:`ENABLED` false."""
    if not ENABLED:
        return None
    found = openblas()
    return found if found is not None and found.has_lapack else None


@contextlib.contextmanager
def disabled() -> Iterator[None]:
    """Force the numpy fallback inside the block (tests compare both paths)."""
    global ENABLED
    previous = ENABLED
    ENABLED = False
    try:
        yield
    finally:
        ENABLED = previous
