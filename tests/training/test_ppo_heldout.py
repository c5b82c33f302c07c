"""PPO's learning curves of held-out success, and the masks its vector env brings with each step."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest

pytest.importorskip("sb3_contrib")

from matplotlib import colors
from PIL import Image

from training.learners import runs
from training.learners.heldout import heldout_success
from training.learners.options import PPOOptions
from training.learners.ppo import make_vec_env, train_ppo
from training.pictures.benchmark import plot_ppo_curves

TINY = PPOOptions(steps=64, n_steps=32, batch_size=16, n_epochs=1, hidden=16, checkpoint_every=32, seed=3,
                  eval_every=32, eval_episodes=3)  # fmt: skip


def test_ppo_rows_hold_the_heldout_success_every_eval_every_steps(tmp_path: Path) -> None:
    rows = train_ppo("basic", TINY, tmp_path / "run", progress=False)
    assert [row["steps"] for row in rows] == [32, 64]
    assert all(0.0 <= row["heldout_success"] <= 1.0 and row["heldout_cost"] >= 0.0 for row in rows)
    assert 0 < rows[0]["eval_seconds"] < rows[1]["eval_seconds"]
    saved = runs.read_metrics(tmp_path / "run")
    assert [row["heldout_success"] for row in saved] == [row["heldout_success"] for row in rows]
    # The last point is the finished run's policy on the same seeds (what the run folder loads as).
    from training.learners.imitation import load_network_policy

    again = heldout_success(load_network_policy(tmp_path / "run"), "basic", TINY.eval_episodes)
    assert again == (rows[-1]["heldout_success"], rows[-1]["heldout_cost"])


def test_ppo_without_evaluations_leaves_the_heldout_columns_empty(tmp_path: Path) -> None:
    options = PPOOptions(**{**TINY.__dict__, "eval_episodes": 0, "steps": 32})
    rows = train_ppo("basic", options, tmp_path / "run", progress=False)
    assert len(rows) == 1 and math.isnan(rows[0]["heldout_success"]) and rows[0]["eval_seconds"] == 0.0


@pytest.mark.parametrize("envs", [1, 2])
def test_the_masks_from_the_steps_are_the_envs_own_through_autoresets(envs: int) -> None:
    venv = make_vec_env("basic", envs)
    try:
        venv.seed(11)
        venv.reset()
        rng, ends = np.random.default_rng(0), 0
        for _ in range(40):
            masks = venv.env_method("action_masks")
            own = venv.venv.env_method("action_masks")  # asked of the envs themselves (a round trip each)
            assert all(np.array_equal(a, b) for a, b in zip(masks, own, strict=True))
            actions = np.array([rng.choice(np.flatnonzero(mask)) for mask in masks])
            _obs, _rewards, dones, infos = venv.step(actions)
            ends += int(dones.sum())
            assert not any("next_action_mask" in info for info in infos)
        assert ends >= 2  # episodes ended and the envs reset themselves in between
    finally:
        venv.close()


def _blue(picture: np.ndarray) -> np.ndarray:
    return np.abs(picture.astype(float) - np.array(colors.to_rgb("C0")) * 255).max(axis=2) < 60


def test_the_curve_plot_shows_heldout_success_where_it_was_measured(tmp_path: Path) -> None:
    rows = [{"steps": 256.0 * k, "seconds": 2.0 * k, "success": 0.9, "return": 1.0 + k,
             "heldout_success": 0.2 * k if k % 2 == 0 else math.nan} for k in range(1, 7)]  # fmt: skip
    trained = [{key: row[key] for key in ("steps", "seconds", "success", "return")} for row in rows]
    for name, curve in (("with", rows), ("without", trained)):
        path = plot_ppo_curves([("ppo", [curve])], tmp_path / f"{name}.png")
        near = _blue(np.asarray(Image.open(path).convert("RGB")))
        height, width = near.shape
        top_right = near[: height // 3, width // 2 :]  # held-out success against seconds (no legend there)
        assert (top_right.sum() > 20) == (name == "with")


def test_a_run_folder_from_before_heldout_evaluations_resumes_and_gains_them(tmp_path: Path) -> None:
    """Options without ``eval_every`` and ``eval_episodes`` (written before they existed) resume at the defaults."""
    options = PPOOptions(**{**TINY.__dict__, "eval_every": 2048, "eval_episodes": 50})  # the defaults
    train_ppo("basic", PPOOptions(**{**options.__dict__, "steps": 32, "eval_episodes": 0}), tmp_path / "run",
              progress=False)  # fmt: skip
    config = runs.read_saved(tmp_path / "run")
    for name in ("envs", "eval_every", "eval_episodes"):
        del config["options"][name]
    config["options"]["steps"], config["data"]["steps"], config["complete"] = 64, 64, False
    (tmp_path / "run" / runs.CONFIG_FILE).write_text(json.dumps(config))
    rows = train_ppo("basic", options, tmp_path / "run", resume=True, progress=False)
    assert [row["steps"] for row in rows] == [32, 64] and 0.0 <= rows[-1]["heldout_success"] <= 1.0
    with pytest.raises(runs.RunFolderError, match="other options"):
        train_ppo("basic", PPOOptions(**{**options.__dict__, "eval_episodes": 3}), tmp_path / "run", resume=True)


def test_rows_written_before_the_heldout_columns_gain_them() -> None:
    from training.learners.ppo_curves import _with_heldout_columns

    rows = [{"steps": 32, "seconds": 1.0}]
    _with_heldout_columns(rows)
    assert math.isnan(rows[0]["heldout_success"]) and math.isnan(rows[0]["heldout_cost"])
    assert rows[0]["eval_seconds"] == 0.0
