"""Does projecting the expert's inexpressible moves onto candidates cost it anything? Seed by seed.

An expert move no candidate expresses is recorded in phase datasets as the allowed move
nearest it (:func:`training.policies.phase_expert.nearest_move`). :func:`check_projection`
runs the expert through that projection and on its own on the same seeds, and
``python -m benchmarks projection --family F --episodes N`` prints the figures (success,
projected moves per episode, extra travel cost).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from expert import ExpertPolicy
from training.data.expert_labels import expert_episode
from training.envs import make_env
from training.policies.phase_expert import PhaseExpert
from training.rollout import run_episode


@dataclass(frozen=True)
class ProjectionCheck:
    """One seed: the expert through the projection against its own episode (costs in metres)."""

    seed: int
    success: bool  # the projected episode delivered everything
    projected: int  # expert moves projected onto a candidate
    steps: int  # actions of the projected episode
    cost: float  # travel cost of the projected episode (info["travel_cost"])
    expert_success: bool  # the expert's own episode (env actions) delivered everything
    expert_cost: float  # its travel cost


def check_projection(
    family: str, seeds: range | list[int], *, time_limit: float = 10.0, rule: str = "end"
) -> list[ProjectionCheck]:
    """Run the expert through the projection and on its own (env actions) on each seed of ``family``."""
    env = make_env("phases", family=family)
    rows = []
    try:
        for seed in seeds:
            own = expert_episode(env, ExpertPolicy(env, time_limit=time_limit, interface="env"), seed)
            phase = PhaseExpert(env, time_limit=time_limit, rule=rule)
            episode = run_episode(env, phase, seed)
            rows.append(
                ProjectionCheck(
                    seed=seed,
                    success=bool(episode.info.get("is_success", False)),
                    projected=phase.projected,
                    steps=episode.figures.steps,
                    cost=float(episode.info.get("travel_cost", 0.0)),
                    expert_success=own.success,
                    expert_cost=own.travel_cost,
                )
            )
    finally:
        env.close()
    return rows


def summarise_projection(rows: list[ProjectionCheck]) -> dict[str, float]:
    """Success rates, projected moves per episode and the extra travel cost where both episodes succeeded."""
    both = [r for r in rows if r.success and r.expert_success and r.expert_cost > 0]
    extra = np.array([r.cost / r.expert_cost - 1.0 for r in both]) if both else np.zeros(0)
    return {
        "episodes": len(rows),
        "success": float(np.mean([r.success for r in rows])),
        "expert_success": float(np.mean([r.expert_success for r in rows])),
        "projected_per_episode": float(np.mean([r.projected for r in rows])),
        "episodes_with_projection": float(np.mean([r.projected > 0 for r in rows])),
        "extra_cost_mean": float(extra.mean()) if both else float("nan"),
        "extra_cost_median": float(np.median(extra)) if both else float("nan"),
        "extra_cost_max": float(extra.max()) if both else float("nan"),
        "extra_cost_projected_mean": float(np.mean([e for e, r in zip(extra, both, strict=True) if r.projected]))
        if any(r.projected for r in both)
        else float("nan"),
    }
