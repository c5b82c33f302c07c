"""A throwaway learned baseline, registered the documented way by ``test_learner_registry.py``.

Its "training" writes a run folder (``config.json`` only); its policy takes the first
allowed candidate of the candidate-phase interface. One module: the options dataclass,
``train`` and ``load`` (it imports nothing heavy, so the options may live here too).
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import Any

import numpy as np

from fetchcarry_env.errors import InputError
from training.data.generate import check_training_seeds
from training.learners.options import check_family, option, seed_option
from training.learners.registry import Learner

KIND = "first-allowed"


@dataclass(frozen=True)
class FirstAllowedOptions:
    """What ``fetchcarry train first-allowed`` takes."""

    family: str = option(help="scenario family (basic, push, ...)", metavar="NAME")
    seed: int = seed_option()

    def __post_init__(self) -> None:
        check_family(self.family)


def train(family: str, seed: int, out: str) -> None:
    """Write the run folder ``out`` (the options' fields and ``out`` as keyword arguments)."""
    folder = Path(out)
    if (folder / "config.json").exists():
        raise InputError(f"{out} already holds a run: choose another folder")
    folder.mkdir(parents=True, exist_ok=True)
    config = {"kind": KIND, "interface": "phases", "options": asdict(FirstAllowedOptions(family, seed)),
              "complete": True}  # fmt: skip
    (folder / "config.json").write_text(json.dumps(config, indent=2) + "\n")


def refuse(options: FirstAllowedOptions) -> None:
    """Its refusal of evaluation data: ``--seed`` (the seed its run would draw episodes from) below 10^9."""
    check_training_seeds(options.seed, 1)


class FirstAllowedPolicy:
    """The first allowed candidate (the masks given, or the env's)."""

    def __init__(self, env: Any = None) -> None:
        self.env = env

    def predict(self, observation: Any, state: Any = None, episode_start: np.ndarray | None = None,
                deterministic: bool = False, action_masks: np.ndarray | None = None) -> tuple[Any, Any]:  # fmt: skip
        """The index of the first allowed candidate (one observation)."""
        if action_masks is None:
            action_masks = self.env.get_wrapper_attr("action_masks")()
        return int(np.flatnonzero(action_masks)[0]), state


def load(path: Path, env: Any) -> FirstAllowedPolicy:
    """The policy of a run folder of this kind."""
    saved = json.loads((path / "config.json").read_text())
    if not saved.get("complete"):
        raise InputError(f"{path} is not a finished run")
    return FirstAllowedPolicy(env)


LEARNER = Learner(
    KIND,
    FirstAllowedOptions,
    train=f"{__name__}:train",
    load=f"{__name__}:load",
    help="the first allowed candidate (a test's throwaway learner)",
    refuse=f"{__name__}:refuse",
    resumable=False,
)
