"""The 3D viewport sidebar panel and menu entries; drawing only, no numerics."""

from __future__ import annotations
