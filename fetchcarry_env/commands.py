"""The environment's commands: ``fetchcarry bench env``.

Registered into ``training/cli.py`` by :func:`register`; the benchmark itself lives in
:mod:`fetchcarry_env.bench` (also ``python -m fetchcarry_env.bench``).
"""

from __future__ import annotations

import argparse


def register(commands: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``bench env`` to the ``fetchcarry`` parser (the env adds no top-level command)."""
    from fetchcarry_env import bench as env_bench

    env_bench.register(bench)
