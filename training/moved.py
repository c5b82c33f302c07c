"""Where the modules of fetchcarry 0.1 went: their old import paths keep working, with a ``DeprecationWarning``.

``import training.baselines.bc`` gives the module now at :mod:`training.learners.bc`
(the very same module object), so code and notebooks written against 0.1 run
unchanged. The table is the whole story of the move; new code imports the new paths.
"""

from __future__ import annotations

import importlib
import importlib.abc
import importlib.machinery
import sys
import warnings
from types import ModuleType

MOVED: dict[str, str] = {
    "training.baselines": "training.learners",
    "training.baselines.bc": "training.learners.bc",
    "training.baselines.configs": "training.learners.options",
    "training.baselines.dagger": "training.learners.dagger",
    "training.baselines.encoders": "training.learners.encoders",
    "training.baselines.ensemble": "training.learners.ensemble",
    "training.baselines.imitation": "training.learners.imitation",
    "training.baselines.ppo": "training.learners.ppo",
    "training.baselines.runs": "training.learners.runs",
    "training.baselines.greedy": "training.policies.greedy",
    "training.baselines.random_phases": "training.policies.random",
    "training.learning": "training.evaluation",
    "training.learning.checks": "benchmarks.studies.learning",
    "training.learning.evaluate": "training.learners.heldout",
    "training.learning.expert_phases": "benchmarks.studies.projection",
    "training.learning.phase_bench": "benchmarks.speed.phases",
    "training.phase_recording": "training.policies.phase_expert",
    "training.sources": "training.data.sources",
    "training.generate": "training.data.generate",
    "training.staging": "training.data.staging",
    "training.datasets": "training.data.datasets",
    "training.evaluate_expert": "training.evaluation.expert",
}
"""Old module path -> new module path."""


class _MovedFinder(importlib.abc.MetaPathFinder, importlib.abc.Loader):
    """Finds a moved module under its old name and hands out the module of its new name."""

    def find_spec(
        self, fullname: str, path: object = None, target: object = None
    ) -> importlib.machinery.ModuleSpec | None:
        if fullname not in MOVED:
            return None
        return importlib.machinery.ModuleSpec(fullname, self, is_package=True)

    def create_module(self, spec: importlib.machinery.ModuleSpec) -> ModuleType:
        warnings.warn(
            f"{spec.name} moved to {MOVED[spec.name]}; the old path will go in a later release",
            DeprecationWarning,
            stacklevel=2,
        )
        return importlib.import_module(MOVED[spec.name])

    def exec_module(self, module: ModuleType) -> None:
        """The new module is already imported: nothing to run."""


def install() -> None:
    """Let the old paths import (once per process)."""
    if not any(isinstance(finder, _MovedFinder) for finder in sys.meta_path):
        sys.meta_path.insert(0, _MovedFinder())  # before the path finder, which would load a second copy
