"""Operators: thin over :mod:`..core` and :mod:`..scene` — read the scene, call the engine, write results back."""

from __future__ import annotations
