"""MaskablePPO's learning curves: a ``metrics.csv`` row per rollout, with the success on held-out seeds.

:func:`curves_callback` is the SB3 callback of ``fetchcarry train ppo``. After every
rollout and the update made on it, ``metrics.csv`` gains a row: the env steps, the wall-clock seconds of training
(``seconds``: rollouts and updates; the held-out evaluations are left out and counted in
``eval_seconds``), and the training episodes finished in that rollout (``success``,
``return`` in the learning reward, ``paper_return``, ``travel_cost`` in metres). Every
``eval_every`` env steps, and after the last rollout, the actor is also evaluated on
``eval_episodes`` held-out seeds of the run's family (:data:`HELDOUT_SEED_BASE` + k,
never a training episode's): ``heldout_success`` and ``heldout_cost`` (the mean travel
cost of those episodes, metres); rows without an evaluation hold NaN there. The policy
evaluated is the one the finished run folder loads as (``BCPolicy`` of the actor, its
highest-scoring allowed candidate, :func:`~training.learners.imitation.load_network_policy`),
so the curve's last point is what ``fetchcarry benchmark`` runs.
"""

from __future__ import annotations

import copy
import math
import time
from collections.abc import Callable
from pathlib import Path
from typing import Any

import numpy as np

from fetchcarry_env.observation import Capacity
from training.learners import runs
from training.learners.heldout import heldout_success
from training.learners.options import PPOOptions

HELDOUT_COLUMNS = ("heldout_success", "heldout_cost", "eval_seconds")  # columns every row has (NaN: no evaluation)


def heldout_evaluator(
    folder: Path, family: str, capacity: Capacity, episodes: int, env_options: dict[str, Any] | None = None
) -> Callable[[Any], dict]:
    """A function of a MaskablePPO model: its actor's held-out success and cost, as ``metrics.csv`` columns.

    ``env_options``: the run's observation mode and image options (None: the state).
    """
    from training.learners.bc import BCPolicy

    def evaluate(model: Any) -> dict[str, float]:
        config = runs.network_config(runs.read_config(folder))  # what the finished run folder loads with
        policy = BCPolicy(copy.deepcopy(model.policy.action_net), config, capacity)  # (BCPolicy edits its network)
        success, cost = heldout_success(policy, family, episodes, **(env_options or {}))
        return {"heldout_success": success, "heldout_cost": cost}

    return evaluate


def _with_heldout_columns(rows: list[dict[str, Any]]) -> None:
    """Rows of a run folder written before the held-out columns existed gain them (NaN), so all rows have one shape."""
    for row in rows:
        for column in HELDOUT_COLUMNS:
            row.setdefault(column, 0.0 if column == "eval_seconds" else math.nan)


def curves_callback(rows: list[dict[str, Any]], folder: Path, options: PPOOptions, bar: Any,
                    evaluate: Callable[[Any], dict], save: Callable[[Any], None]) -> Any:  # fmt: skip
    """The SB3 callback that appends a row to ``rows`` per rollout (``metrics.csv``), evaluates and checkpoints.

    ``rows`` are the rows so far (a resumed run's); ``evaluate(model)`` gives the held-out
    columns; ``save(model)`` writes a checkpoint (every ``options.checkpoint_every`` steps).
    """
    from stable_baselines3.common.callbacks import BaseCallback

    _with_heldout_columns(rows)
    last = rows[-1] if rows else {}

    class Curves(BaseCallback):
        """Rows of learning curves per rollout, held-out evaluations, checkpoints, the progress bar."""

        def __init__(self) -> None:
            super().__init__()
            self.returns = self.paper = 0.0
            self.finished: list[tuple[bool, float, float, float]] = []
            self.row: dict[str, Any] | None = None  # the last rollout's row, until its update is done
            self.saved_at = last.get("steps", 0)
            self.episodes = int(last.get("episodes", 0))
            evaluated = [row["steps"] for row in rows if row["heldout_success"] == row["heldout_success"]]
            self.evaluated_at = evaluated[-1] if evaluated else 0
            self.eval_seconds = float(last.get("eval_seconds", 0.0))
            self.started = time.perf_counter() - float(last.get("seconds", 0.0)) - self.eval_seconds

        def _on_step(self) -> bool:
            infos, rewards, dones = self.locals["infos"], self.locals["rewards"], self.locals["dones"]
            if isinstance(self.returns, float):  # one running sum per env, from the first step on
                self.returns, self.paper = np.zeros(len(infos)), np.zeros(len(infos))
            for i, info in enumerate(infos):  # in env order: the rows do not depend on the workers' timing
                self.returns[i] += float(rewards[i])
                self.paper[i] += float(info.get("paper_reward", 0.0))
                if dones[i]:
                    self.finished.append((bool(info.get("is_success")), float(self.returns[i]),
                                          float(self.paper[i]), float(info.get("travel_cost", 0.0))))  # fmt: skip
                    self.returns[i] = self.paper[i] = 0.0
            bar.update(len(infos))
            return True

        def _on_rollout_end(self) -> None:
            """The rollout's training columns; its row is finished once the update it feeds is done."""
            done, steps = self.finished, self.num_timesteps
            self.episodes += len(done)
            self.row = {"steps": steps, "seconds": math.nan, "episodes": self.episodes, **_training_columns(done)}
            self.finished = []

        def _on_rollout_start(self) -> None:
            self._finish_row()  # the previous rollout's: SB3 updated the model on it in between

        def _on_training_end(self) -> None:
            self._finish_row()  # the last rollout's, after its update: the weights the run folder saves

        def _finish_row(self) -> None:
            """Append the last rollout's row, with the held-out columns of the updated actor when due; write and
            checkpoint."""
            if self.row is None:
                return
            row, steps, self.row = self.row, self.row["steps"], None
            row["seconds"] = time.perf_counter() - self.started - self.eval_seconds
            due = steps - self.evaluated_at >= options.eval_every or steps >= options.steps
            heldout = {"heldout_success": math.nan, "heldout_cost": math.nan}
            if options.eval_episodes > 0 and due:
                clock = time.perf_counter()
                heldout = evaluate(self.model)
                self.eval_seconds += time.perf_counter() - clock
                self.evaluated_at = steps
                bar.set_postfix_str(f"held-out success {heldout['heldout_success']:.0%}", refresh=False)
            rows.append({**row, **heldout, "eval_seconds": self.eval_seconds})
            runs.write_metrics(folder, rows)
            if steps - self.saved_at >= options.checkpoint_every:
                save(self.model)
                self.saved_at = steps

    return Curves()


def _training_columns(done: list[tuple[bool, float, float, float]]) -> dict[str, float]:
    """The rollout's finished training episodes: success rate, mean return, paper return, travel cost (NaN: none)."""
    names = ("success", "return", "paper_return", "travel_cost")
    return {name: float(np.mean([d[k] for d in done])) if done else math.nan for k, name in enumerate(names)}
