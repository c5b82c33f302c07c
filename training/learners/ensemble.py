"""Ensembles: several trained run folders combined into one policy, itself a run folder (``kind`` ``ensemble``).

The members' networks score the same candidates; the ensemble acts on the mean of their
log-probabilities (:class:`training.learners.encoders.Ensemble`), with its own episode
memory (``avoid_repeats``, ``avoid_returns``). Nothing is trained: :func:`make_ensemble`
copies the members' weights into the new folder's ``model.pt`` and each member's network
settings into its ``config.json`` (``options.members``), so the folder loads on its
own, moved or with the members gone.

Measured on 200 new ``push`` scenarios (``docs/benchmarks/learning.md``): the published
table's ensemble of three ``dagger-aimed`` runs solved 98.5 % at a cost ratio of 1.15
where its members solved 90.5-93.5 % at 1.18-1.20. A decision runs every member (1.08 ms
for three flat MLPs, against 0.7 ms for one).
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import replace
from pathlib import Path

from training.learners import runs
from training.learners.bc import BCPolicy
from training.learners.encoders import Ensemble
from training.learners.runs import RunFolderError

SHARED_KEYS = ("capacity", "candidates", "features")  # what every member must have alike


def make_ensemble(members: Sequence[str | Path], out: str | Path, *, avoid_returns: bool = True) -> BCPolicy:
    """Combine the complete run folders ``members`` (bc, dagger or ppo) into the new run folder ``out``.

    The ensemble keeps the first member's acting settings, with ``avoid_repeats`` on and
    ``avoid_returns`` as given. Raises ``ValueError`` when fewer than two members are
    given, when one is not a complete run folder or is an ensemble itself, or when their
    observation capacity, candidates or features differ (they would not score the
    same candidates), and when ``out`` holds a run already: all :class:`RunFolderError`
    (bad input, a ``ValueError``). The ``train`` of the ``ensemble`` learner
    (:mod:`training.learners.registry`: the fields of
    :class:`~training.learners.options.EnsembleRun` as keyword arguments).
    """
    if (Path(out) / runs.CONFIG_FILE).exists():
        raise RunFolderError(f"{out} already holds a run: choose another folder")
    paths = [Path(member) for member in members]
    if len(paths) < 2:
        raise RunFolderError(f"an ensemble needs at least two run folders, got {len(paths)}")
    saved = [runs.read_config(path) for path in paths]
    for path, config in zip(paths, saved, strict=True):
        if config["kind"] == "ensemble":
            raise RunFolderError(f"{path} is an ensemble: give its members instead")
        if not config.get("complete"):
            raise RunFolderError(f"{path} is not a finished run: resume it first")
        for key in SHARED_KEYS:
            if config[key] != saved[0][key]:
                raise RunFolderError(f"{path} has another {key} than {paths[0]}: its network scores other candidates")
    policies = [runs.load_policy(path) for path in paths]
    config = replace(policies[0].config, avoid_repeats=True, avoid_returns=avoid_returns)
    listed = [{"run": str(p), "kind": c["kind"], "config": c["config"]} for p, c in zip(paths, saved, strict=True)]
    options = {"members": listed, "avoid_returns": avoid_returns}
    first, data = saved[0], {"members": [s.get("data", {}) for s in saved]}
    config_json = runs.run_config("ensemble", options, config, policies[0].capacity, first["candidates"],
                                  first["features"], data)  # fmt: skip
    folder, _ = runs.start_run(out, config_json, resume=False)
    network = Ensemble([policy.network for policy in policies])
    runs.finish_run(folder, network, config_json)
    return BCPolicy(network, config, policies[0].capacity)
