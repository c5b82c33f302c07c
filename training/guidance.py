"""A policy's rollout as a plan: the guide of :func:`expert.plan` (``plan(scenario, guide=...)``).

:func:`rollout_plan` runs a policy (a run folder of ``fetchcarry train``, ``greedy``, any
name :func:`training.resolve.resolve` takes) for one episode on a fixed scenario, in the
env (no physics), and writes every step it took as a phase of a
:class:`~expert.plans.Plan`: the env's action of the step (its lattice cell, heading,
posture and mode; for a candidate index, the env action the candidate stood for) is the
phase, as in :mod:`expert.to_actions` read backwards, and the states before and after
the step name the phase's target (the object picked or placed, the clutter pushed).
Steps the env refused are left out. The plan's status is ``feasible`` when the episode
delivered everything, else ``time_limit`` with the phases it did (a partial guide is
still a branching hint).

Units: metres, seconds.
"""

from __future__ import annotations

import time
from typing import Any

import numpy as np

from expert.plans import Phase, Plan, task_cost
from fetchcarry_env.actions import Mode
from fetchcarry_env.geometry import HEADINGS
from fetchcarry_env.observation import Capacity, WorldState
from fetchcarry_env.scenario import Scenario
from training.envs import make_env
from training.resolve import build, resolve
from training.rollout import run_episode

ACTIONS = {Mode.MOVE: "move", Mode.PICK: "pick", Mode.PLACE: "place", Mode.PUSH: "push"}
ROLLOUT_SEED = 0  # the reset seed (a fixed scenario draws nothing from it; a random policy is seeded by it)


def rollout_plan(policy: str, scenario: Scenario) -> Plan:
    """``policy``'s episode on ``scenario`` as a plan; ``stats`` has ``rollout_s``, ``policy``, ``delivered``.

    Raises :class:`~training.errors.BenchmarkError` for a policy name that names nothing.
    """
    spec = resolve(policy)
    options = dict(spec.env_options)
    capacity = options.pop("capacity", None)  # a run's own slots, grown to hold the scenario (a set encoder reads any)
    capacity = Capacity(**capacity) if isinstance(capacity, dict) else capacity or Capacity()
    env = make_env(spec.interface, scenario=scenario.to_dict(), capacity=capacity.holding(scenario), **options)
    started = time.perf_counter()
    actions: list[np.ndarray | None] = []
    candidates = spec.interface == "phases"
    to_env = env.get_wrapper_attr("env_action") if candidates else None

    def observe(observation: Any, action: Any, mask: Any) -> None:
        actions.append(to_env(action) if to_env is not None else np.asarray(action))

    try:
        agent = build(spec, env)
        record = run_episode(env, agent, ROLLOUT_SEED, observe=observe, stop_on_failure=False)
    finally:
        env.close()
    phases = episode_phases(scenario, record.states, actions, record.infos["invalid_action"][1:])
    delivered = bool(record.info.get("is_success"))
    stats = {"policy": spec.name, "rollout_s": time.perf_counter() - started, "delivered": delivered}
    objective = task_cost(scenario, phases) if delivered else None
    return Plan(scenario.name, "feasible" if delivered else "time_limit", objective, phases, stats)


def episode_phases(
    scenario: Scenario, states: list[WorldState], actions: list[np.ndarray | None], refused: Any
) -> tuple[Phase, ...]:
    """The phases of an episode: ``states`` (after reset and after each step), each step's env action, refusals."""
    start = states[0]
    phases = [_phase(start, "start", None, None)]
    for before, after, action, was_refused in zip(states, states[1:], actions, refused, strict=False):
        if action is None or bool(was_refused):
            continue
        mode = Mode(int(action[4]))
        kind = ACTIONS[mode]
        posture = None if mode == Mode.MOVE else scenario.robot.postures[int(action[3])].name
        phases.append(_phase(after, kind, _target(kind, before, after), posture))
    return tuple(phases)


def _target(kind: str, before: WorldState, after: WorldState) -> str | None:
    """The object picked or placed, or the clutter pushed, from the states around the step."""
    if kind == "pick":
        return after.holding
    if kind == "place":
        return before.holding
    if kind == "push":
        shift = {c: float(np.hypot(*np.subtract(p, before.clutter[c]))) for c, p in after.clutter.items()}
        moved = max(shift, key=shift.get, default=None)
        return moved if moved is not None and shift[moved] > 1e-6 else None
    return None


def _phase(state: WorldState, action: str, target: str | None, posture: str | None) -> Phase:
    objects = {k: (float(v[0]), float(v[1])) for k, v in state.objects.items()}
    clutter = {k: (float(v[0]), float(v[1])) for k, v in state.clutter.items()}
    heading = state.heading if state.heading in HEADINGS else HEADINGS[0]
    base = (float(state.base[0]), float(state.base[1]))
    return Phase(base, heading, action, target, posture, state.holding, objects, clutter)
