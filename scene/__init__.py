"""Bridge between Blender data and the engine: curve objects in, mesh objects, shape keys and files out.

This is the only place (with ``operators`` and ``panels``) that touches ``bpy`` data; :mod:`..core` never does.
"""

from __future__ import annotations
