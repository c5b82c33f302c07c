"""Shared fixtures: the spec's example scenario, a private Minari folder."""

from __future__ import annotations

import copy
import json
from pathlib import Path

import pytest

from fetchcarry_env import Scenario

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"


@pytest.fixture
def spec_example_dict() -> dict:
    """The scenario of docs/scenario-format.md (a fresh deep copy each time)."""
    return copy.deepcopy(json.loads((EXAMPLES / "push_basic.json").read_text()))


@pytest.fixture
def spec_example(spec_example_dict: dict) -> Scenario:
    return Scenario.from_dict(spec_example_dict)


@pytest.fixture
def minari_root(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Path:
    """A private MINARI_DATASETS_PATH under the test's temporary folder (the training and benchmark tests use it)."""
    root = tmp_path / "minari"
    root.mkdir()
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(root))
    return root
