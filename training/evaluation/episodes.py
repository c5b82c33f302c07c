"""One benchmark episode: a policy acts in one scenario until it succeeds or runs out of phases.

:func:`benchmark_episode` is what the workers run: one pass of the episode loop
(:func:`training.rollout.run_episode`), whose figures and final ``info`` become one
record (a plain dict, the shape of ``results.json``'s records; their schema is
:mod:`training.evaluation.results`, docs/results-format.md):

============== =====================================================================
key            value
============== =====================================================================
policy         the policy's label
scenario       the scenario's name
split          the split's name (``iid-v0``), or ``scenarios:FOLDER``
source         the family it was drawn from, or its file name
seed           the reset seed (and the random policy's seed for the episode)
digest         the sha256 (hex) of the scenario's canonical JSON
               (:func:`training.evaluation.results.scenario_digest`): what ``--resume``
               matches, so a scenario file that changed runs again
success        every object at its goal and the hand empty (``info["is_success"]``)
delivered      objects at their goals at the end (``info["delivered"]``)
objects        objects in the scenario
cost           the episode's task cost (``info["task_cost"]``): its travel plus 10 per
               object and step not at the goal plus its penalties, minus its return
travel         the paper's travel cost of the episode, metres (``info["travel_cost"]``)
expert_cost    the reference's cost on the same scenario (filled in by the benchmark: the
               proven optimum; ``null`` where the expert failed)
return         the env's reward summed over the episode: minus the task cost
phases         decisions taken (env steps)
pushes         steps that pushed a piece of clutter (``info["push"]`` present)
invalid_actions steps the env refused (``info["invalid_action"]`` not ``None``)
contacts       stops at a contact (the env's ``info["collisions"]`` at the end)
decision_ms    mean wall time of the policy's ``predict`` per decision, milliseconds
               (for the expert: the planner's time per decision)
mask_ms        mean wall time per decision of the env's ``action_masks()`` handed to
               the policy, milliseconds (0 for a policy whose ``predict`` takes no
               ``action_masks=``: the expert reads what it needs from the env)
step_ms        mean wall time of a whole step per decision, milliseconds: the policy,
               the mask and the env (its ``step``, and its ``reset`` spread over the steps)
============== =====================================================================
"""

from __future__ import annotations

import sys
from typing import Any

import gymnasium as gym

from training.envs import make_env
from training.evaluation.results import scenario_digest
from training.evaluation.splits import EvalScenario
from training.resolve import PolicySpec, build
from training.rollout import run_episode

# One env and policy per policy spec in each process, reused episode after episode (an
# env's reset rebuilds only what changed). A worker process runs one task at a time.
_BUILT: dict[str, tuple[gym.Env, Any]] = {}
_MAX_BUILT = 4
_TORCH_THREADS: list[int] = []  # torch's thread count before the benchmark set it to one (restored by close_all)


def _built(spec: PolicySpec, item: EvalScenario) -> tuple[gym.Env, Any]:
    """The env and the policy of ``spec`` for ``item``'s floor in this process (built once, reused episode after
    episode: every scenario of a split shares the families' extent)."""
    key = repr((spec, item.floor.get("scenario")))
    if key not in _BUILT:
        if len(_BUILT) >= _MAX_BUILT:
            env, _ = _BUILT.pop(next(iter(_BUILT)))
            env.close()
        env = make_env(spec.interface, **item.floor, **spec.env_options)
        policy = build(spec, env)
        _one_torch_thread()
        _BUILT[key] = (env, policy)
    return _BUILT[key]


def benchmark_episode(spec: PolicySpec, item: EvalScenario, deterministic: bool = True) -> dict[str, Any]:
    """One episode of ``spec`` on ``item``'s scenario; its record (see the module docstring)."""
    env, policy = _built(spec, item)
    episode = run_episode(env, policy, item.seed, options={"scenario": item.scenario},
                                  deterministic=deterministic, stop_on_failure=False)  # fmt: skip
    figures, info = episode.figures, episode.info
    return {
        "policy": spec.name,
        "scenario": item.scenario.name,
        "split": item.split,
        "source": item.source,
        "seed": item.seed,
        "digest": scenario_digest(item.scenario),
        "success": bool(info["is_success"]),
        "delivered": int(info["delivered"]),
        "objects": len(item.scenario.objects),
        "cost": float(info["task_cost"]),
        "travel": float(info["travel_cost"]),
        "expert_cost": None,
        "return": figures.episode_return,
        "phases": figures.steps,
        "pushes": figures.pushes,
        "invalid_actions": figures.invalid_actions,
        "contacts": int(info["collisions"]),
        "decision_ms": 1000.0 * figures.policy_s / figures.steps,
        "mask_ms": 1000.0 * figures.mask_s / figures.steps,
        "step_ms": 1000.0 * (figures.policy_s + figures.mask_s + figures.simulation_s) / figures.steps,
    }


def run_task(task: tuple[PolicySpec, EvalScenario]) -> dict[str, Any]:
    """``benchmark_episode(*task)``: the picklable unit of work the process pool and Ray run."""
    return benchmark_episode(*task)


def _one_torch_thread() -> None:
    """Run torch (if a policy loaded it) on one thread: a decision is measured on one core.

    On this 2-core machine under load, two torch threads made a small set encoder's
    decision about 100 times slower (220 ms against 2 ms, docs/benchmarks/benchmark.md).
    """
    torch = sys.modules.get("torch")
    if torch is not None and torch.get_num_threads() != 1:
        _TORCH_THREADS.append(torch.get_num_threads())
        torch.set_num_threads(1)


def close_all() -> None:
    """Close the envs this process built and give torch back its threads (safe to call twice)."""
    while _BUILT:
        _, (env, _) = _BUILT.popitem()
        env.close()
    torch = sys.modules.get("torch")
    if torch is not None and _TORCH_THREADS:
        torch.set_num_threads(_TORCH_THREADS[0])
        _TORCH_THREADS.clear()
