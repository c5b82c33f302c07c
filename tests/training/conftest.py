"""Fixtures of the training tests: a private Minari folder for every test."""

from __future__ import annotations

from pathlib import Path

import pytest


@pytest.fixture(autouse=True)
def private_minari(minari_root: Path) -> Path:
    """Every test writes its datasets under its own temporary MINARI_DATASETS_PATH (``minari_root``)."""
    return minari_root
