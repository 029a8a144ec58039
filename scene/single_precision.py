"""Blender keeps float properties in single precision; the engine, its defaults and the command line work with the
decimals a designer types. :func:`as_typed` turns one into the other."""

from __future__ import annotations


def as_typed(value: float) -> float:
    """A single-precision property's value as the decimal it shows, rounded to its 7 significant digits (0.7, not
    0.699999988079071; a unit scale of 0.001, not 0.0010000000474974513). With the raw values a Re-fold with the
    default stiffnesses solved a model 1e-8 apart from the Fold's, and at a unit scale of 0.001 every imported point
    moved by up to 9.5e-6 mm: on a pattern that stops at the round-off floor, other iterations (116 or 113 instead of
    159) and a vertex 3 mm away. The curves' unit scale was read this way already; the fold mesh's was not."""
    return float(f"{float(value):.7g}")
