"""Subcommands of the command line, one module each (``discretize``, ``fold``)."""

from __future__ import annotations

import argparse


def register(sub: argparse._SubParsersAction) -> None:
    """Add every subcommand's parser to ``sub``."""
    from . import discretize, fold

    discretize.register(sub)
    fold.register(sub)
