"""The staging folder keeps each finished episode whole, and reads it back unchanged."""

from __future__ import annotations

from pathlib import Path

import numpy as np

from training.data.staging import Staging
from training.rollout import INFO_KEYS, EpisodeFigures, EpisodeRecord


def _record(seed: int, steps: int) -> EpisodeRecord:
    rng = np.random.default_rng(seed)
    figures = EpisodeFigures(
        seed=seed, scenario="toy", objects=1, delivered=1, success=True, outcome="delivered", failure=None,
        steps=steps, episode_return=7.5, path_length_m=3.25, collisions=0, invalid_actions=0, planning_s=0.1,
        policy_s=0.2, simulation_s=0.3, plans=1, replans=0, repairs=0, planner_failures=0, objective=None,
    )  # fmt: skip
    return EpisodeRecord(
        seed=seed,
        scenario={"format": "fetchcarry-scenario/1", "name": "toy"},
        observations={"observation": rng.random((steps + 1, 7), dtype=np.float32)},
        actions=rng.integers(0, 5, size=(steps, 5)),
        rewards=rng.random(steps),
        terminations=np.array([False] * (steps - 1) + [True]),
        truncations=np.zeros(steps, dtype=bool),
        infos={key: np.zeros(steps + 1) for key in INFO_KEYS},
        figures=figures,
    )


def test_staged_episode_reads_back_unchanged(tmp_path: Path) -> None:
    staging = Staging("fetchcarry/toy-v0", root=tmp_path)
    staging.start({"family": "push"})
    record = _record(seed=4, steps=3)
    staging.write(7, record)
    back = staging.read(7)
    assert staging.staged() == {7}
    assert staging.manifest() == {"family": "push"}
    assert back.seed == 4 and back.scenario == record.scenario and back.figures == record.figures
    for name in ("actions", "rewards", "terminations", "truncations"):
        assert np.array_equal(getattr(back, name), getattr(record, name))
    assert np.array_equal(back.observations["observation"], record.observations["observation"])
    assert set(back.infos) == set(INFO_KEYS)
    # Only whole files remain: no temporary file is left behind.
    assert sorted(p.name for p in staging.path.iterdir()) == ["episode_000007.npz", "manifest.json"]


def test_remove_clears_the_staging(tmp_path: Path) -> None:
    staging = Staging("toy-v0", root=tmp_path)
    staging.start({})
    staging.write(0, _record(seed=0, steps=2))
    staging.remove()
    assert not staging.exists() and staging.staged() == set()
