"""glTF containers: a binary ``.glb`` turned into one self-contained ``.gltf`` text file, and the check that either
is whole.

Blender's glTF exporter writes a ``.gltf`` as two or more files (the JSON and a ``.bin`` beside it, ``GLTF_SEPARATE``);
its single-file embedded form is hidden behind a preference. Two files cannot replace two old ones all or nothing,
and a designer who asks for ``model.gltf`` expects one file a web viewer opens. So the mesh is exported as GLB
and its binary chunk is embedded here as a base64 ``data:`` URI (glTF 2.0 §3.6.1.1, "Data URI"): the same JSON,
accessors and bytes, one file. Plain data in and out: no Blender.
"""

from __future__ import annotations

import base64
import json
import struct

GLB_MAGIC = b"glTF"
CHUNK_JSON = 0x4E4F534A
CHUNK_BIN = 0x004E4942
DATA_URI = "data:application/octet-stream;base64,"


class GltfError(ValueError):
    """A GLB or glTF that is not whole (the message says what is missing)."""


def glb_chunks(glb: bytes) -> tuple[dict, bytes | None]:
    """The JSON document and the binary chunk (``None`` if there is none) of a GLB file's bytes (glTF 2.0 §4.4)."""
    if len(glb) < 20 or glb[:4] != GLB_MAGIC:
        raise GltfError("not a GLB file (no 'glTF' header)")
    version, length = struct.unpack_from("<II", glb, 4)
    if version != 2 or length != len(glb):
        raise GltfError(f"GLB header says version {version}, {length} bytes; the file has {len(glb)}")
    document, binary, at = None, None, 12
    while at + 8 <= length:
        size, kind = struct.unpack_from("<II", glb, at)
        body = glb[at + 8 : at + 8 + size]
        if len(body) != size:
            raise GltfError(f"GLB chunk at byte {at} says {size} bytes; {len(body)} remain")
        if kind == CHUNK_JSON and document is None:
            document = json.loads(body.decode("utf-8"))
        elif kind == CHUNK_BIN and binary is None:
            binary = bytes(body)
        at += 8 + size
    if document is None:
        raise GltfError("GLB file without a JSON chunk")
    return document, binary


def embedded_gltf(glb: bytes) -> str:
    """The ``.gltf`` text of a GLB file's bytes: its JSON with the binary chunk as the first buffer's data URI.

    A GLB's first buffer is its binary chunk (it has no ``uri``); every other buffer must already carry its own
    ``uri`` (Blender writes one buffer). The chunk's padding (to 4 bytes) is dropped to the buffer's ``byteLength``."""
    document, binary = glb_chunks(glb)
    buffers = document.get("buffers", [])
    if buffers and "uri" not in buffers[0]:
        if binary is None:
            raise GltfError("the GLB's first buffer has no binary chunk")
        size = int(buffers[0].get("byteLength", len(binary)))
        if size > len(binary):
            raise GltfError(f"the GLB's buffer says {size} bytes, its binary chunk holds {len(binary)}")
        buffers[0]["uri"] = DATA_URI + base64.b64encode(binary[:size]).decode("ascii")
    return json.dumps(document, ensure_ascii=False, separators=(",", ":")) + "\n"


def check_embedded_gltf(text: str) -> int:
    """Raise :class:`GltfError` unless ``text`` is a whole glTF JSON whose buffers are embedded data URIs of their
    stated lengths; returns the number of bytes they hold (a cut-short write fails the JSON parse)."""
    try:
        document = json.loads(text)
    except ValueError as exc:
        raise GltfError(f"the glTF file is not whole JSON ({exc})") from None
    total = 0
    for k, buffer in enumerate(document.get("buffers", [])):
        uri = str(buffer.get("uri", ""))
        if not uri.startswith(DATA_URI):
            raise GltfError(f"glTF buffer {k} is not embedded")
        data = base64.b64decode(uri[len(DATA_URI) :], validate=True)
        if len(data) != int(buffer.get("byteLength", -1)):
            raise GltfError(f"glTF buffer {k} holds {len(data)} bytes, says {buffer.get('byteLength')}")
        total += len(data)
    return total
