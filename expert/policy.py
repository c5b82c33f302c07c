"""The MILP expert as a policy: stable-baselines3's ``predict`` protocol over the env's observation.

:class:`ExpertPolicy` plans from the observation alone: the observation holds the whole
geometry (``fetchcarry_env.observation.decode`` rebuilds the scenario and the state), so
the expert can label any state: the start, mid-episode with an object in the hand,
after a push that slid differently in physics, or a state a learner drove into. This
is what DAgger needs.

It keeps its plan while execution follows it: after each action it expects the state
of the next phase of the plan, and it replans when the observed state departs from
that (the base more than ``base_tolerance`` from the planned point, a different
object in the hand, an object or a piece of clutter more than ``item_tolerance`` from
where the plan put it: a push that slid, a move that stopped at a contact), when the
plan is used up before the task is done, and at ``episode_start``.

When the planner gives no plan (infeasible, time limit), the policy returns a
well-defined fallback (a ``move`` to the lattice point nearest the base, keeping the
heading: it does nothing useful and breaks nothing) and does not plan again until the
state changes. :attr:`ExpertPolicy.stats` counts plans, replans, failures, fallbacks
and planning seconds; :attr:`ExpertPolicy.last_decisions` says what the last call did
for each env of the batch.

The policy uses the env only for its lattice and observation capacity (never its
simulation), so it works on a plain env, a wrapped env or an SB3 ``VecEnv``.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field
from typing import Any

import numpy as np

from expert.plans import Phase, Plan
from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.observation import Capacity, WorldState, decode
from fetchcarry_env.scenario import Scenario

DEFAULT_TIME_LIMIT = 10.0  # seconds per planning call, model building included
BASE_TOLERANCE = 0.01  # metres: the base is where the plan put it
ITEM_TOLERANCE = 0.02  # metres: an object or a piece of clutter is where the plan put it


@dataclass(frozen=True)
class ExpertStats:
    """What the expert did since its last :meth:`ExpertPolicy.reset` (all envs of a batch together)."""

    plans: int = 0  # planning calls
    replans: int = 0  # planning calls other than the first of an episode
    failures: int = 0  # planning calls that found no plan (infeasible, time limit)
    fallbacks: int = 0  # actions returned without a plan
    planning_s: float = 0.0  # seconds spent in the planner
    last_status: str | None = None  # status of the last planning call
    last_objective: float | None = None  # objective (Eq. 1) of the last plan found

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class Decision:
    """What one ``predict`` call did for one env."""

    planned: bool  # the planner ran
    replanned: bool  # it ran although an episode was already under way
    reason: str  # why it planned (or did not): "episode_start", "departed: ...", "plan_used_up", "following", ...
    planning_s: float  # seconds spent in the planner
    status: str | None  # the plan's status when it planned, else None
    fallback: bool  # the action is the fallback (no plan)


@dataclass
class _Track:
    """The plan being followed in one env of the batch."""

    actions: list[Action] = field(default_factory=list)  # actions not yet given
    expected: list[Phase] = field(default_factory=list)  # phase reached after each of those actions
    now: Phase | None = None  # the phase the state should be in now
    failed_state: WorldState | None = None  # the state in which planning last failed
    started: bool = False  # the planner already ran in this episode


class ExpertPolicy:
    """The MILP expert behind stable-baselines3's ``predict(observation, state, episode_start, deterministic)``.

    ``env`` is the env (wrapped or not) or a ``VecEnv`` whose observations it will see; its
    ``lattice`` and ``capacity`` fix how actions and observations are laid out (pass them
    explicitly to use the policy without an env). ``time_limit`` (seconds) bounds each
    planning call; ``base_tolerance`` and ``item_tolerance`` (metres) say how far the state
    may drift from the plan before the expert replans. ``planner_options`` go to
    :func:`expert.planner.plan`.
    """

    def __init__(
        self,
        env: Any = None,
        *,
        time_limit: float = DEFAULT_TIME_LIMIT,
        base_tolerance: float = BASE_TOLERANCE,
        item_tolerance: float = ITEM_TOLERANCE,
        lattice: Lattice | None = None,
        capacity: Capacity | None = None,
        **planner_options: Any,
    ) -> None:
        if time_limit <= 0:
            raise ValueError(f"time_limit must be positive (seconds), got {time_limit}")
        if base_tolerance < 0 or item_tolerance < 0:
            raise ValueError("tolerances must not be negative")
        self.lattice = lattice if lattice is not None else _env_attribute(env, "lattice")
        self.capacity = capacity if capacity is not None else _env_attribute(env, "capacity")
        self.time_limit = time_limit
        self.base_tolerance = base_tolerance
        self.item_tolerance = item_tolerance
        self.planner_options = planner_options
        self._tracks: list[_Track] = []
        self._stats = ExpertStats()
        self.last_decisions: list[Decision] = []
        self.last_plan: Plan | None = None

    @property
    def stats(self) -> ExpertStats:
        """Counts and planning time since the last :meth:`reset`."""
        return self._stats

    @property
    def last_decision(self) -> Decision | None:
        """What the last call did for the first (or only) env."""
        return self.last_decisions[0] if self.last_decisions else None

    def reset(self) -> None:
        """Forget every plan and zero the statistics (call it between episodes of a single env)."""
        self._tracks = []
        self._stats = ExpertStats()
        self.last_decisions = []
        self.last_plan = None

    def predict(
        self,
        observation: dict[str, np.ndarray],
        state: Any = None,
        episode_start: np.ndarray | bool | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """The expert's action for each observation: ``(action, state)`` as stable-baselines3 returns them.

        ``observation`` is one observation dict (arrays of the env's shapes) or a batch
        (the same keys, arrays with a leading dimension). ``episode_start`` (one bool per
        env) makes the expert drop its plan for that env. The expert is deterministic;
        ``deterministic`` is accepted for the protocol. ``state`` is returned unchanged.
        """
        flat = np.asarray(observation["observation"] if isinstance(observation, dict) else observation)
        batched = flat.ndim == 2
        rows = flat if batched else flat[None, :]
        starts = np.broadcast_to(
            np.asarray(False if episode_start is None else episode_start, dtype=bool), (len(rows),)
        )
        while len(self._tracks) < len(rows):
            self._tracks.append(_Track())
        decisions, actions = [], []
        for k, row in enumerate(rows):
            action, decision = self._act(self._tracks[k], row, bool(starts[k]))
            actions.append(action.to_array())
            decisions.append(decision)
        self.last_decisions = decisions
        stacked = np.stack(actions)
        return (stacked if batched else stacked[0]), state

    # -- one env ---------------------------------------------------------------------------

    def _act(self, track: _Track, row: np.ndarray, episode_start: bool) -> tuple[Action, Decision]:
        scenario, world = decode(row, self.capacity)
        if episode_start:
            track.__init__()
        reason = self._why_plan(track, scenario, world)
        if reason is None:
            track.now = track.expected.pop(0)
            return track.actions.pop(0), Decision(False, False, "following", 0.0, None, False)
        if reason == "done":
            return self._fallback(world), Decision(False, False, "done", 0.0, None, False)
        if reason == "failed_here":
            self._count(fallbacks=1)
            return self._fallback(world), Decision(False, False, "no plan for this state", 0.0, None, True)

        replanned = track.started
        plan_result, seconds = self._plan(scenario, world)
        track.started = True
        self._count(plans=1, replans=int(replanned), planning_s=seconds, last_status=plan_result.status)
        if not plan_result.found:
            track.__init__(failed_state=world, started=True)
            self._count(failures=1, fallbacks=1)
            return self._fallback(world), Decision(True, replanned, reason, seconds, plan_result.status, True)

        from expert.to_actions import plan_to_actions

        actions = list(plan_to_actions(plan_result, scenario, self.lattice))
        phases = list(plan_result.phases[1:])
        if len(actions) != len(phases):
            raise RuntimeError(f"plan_to_actions gave {len(actions)} actions for {len(phases)} phases")
        self._count(last_objective=plan_result.objective)
        self.last_plan = plan_result
        if not actions:  # the state already solves the task
            track.__init__(started=True)
            return self._fallback(world), Decision(True, replanned, reason, seconds, plan_result.status, False)
        track.actions, track.expected, track.failed_state = actions[1:], phases[1:], None
        track.now = phases[0]
        return actions[0], Decision(True, replanned, reason, seconds, plan_result.status, False)

    def _why_plan(self, track: _Track, scenario: Scenario, world: WorldState) -> str | None:
        """Why the expert must plan now, ``None`` to follow the plan, or "done" / "failed_here"."""
        if track.failed_state is not None and not self._departed(track.failed_state, world, self.lattice.resolution):
            return "failed_here"
        if track.now is None:
            if _solved(scenario, world):
                return "done"
            return "episode_start" if not track.started else "no_plan"
        departure = self._departure(track.now, world)
        if departure is not None:
            return f"departed: {departure}"
        if not track.actions:
            return "done" if _solved(scenario, world) else "plan_used_up"
        return None

    def _departure(self, phase: Phase, world: WorldState) -> str | None:
        """How ``world`` departs from the state ``phase`` promised, beyond the tolerances, or ``None``."""
        gap = math.dist(phase.base, world.base)
        if gap > self.base_tolerance:
            return f"base {gap * 100:.1f} cm from the plan"
        if phase.holding != world.holding:
            return f"holding {world.holding} instead of {phase.holding}"
        for object_id, planned in phase.objects.items():
            if object_id == world.holding or object_id not in world.objects:
                continue
            gap = math.dist(planned, world.objects[object_id][:2])
            if gap > self.item_tolerance:
                return f"{object_id} {gap * 100:.1f} cm from the plan"
        for clutter_id, planned in phase.clutter.items():
            if clutter_id in world.clutter:
                gap = math.dist(planned, world.clutter[clutter_id])
                if gap > self.item_tolerance:
                    return f"{clutter_id} {gap * 100:.1f} cm from the plan"
        return None

    def _departed(self, before: WorldState, now: WorldState, base_tolerance: float) -> bool:
        """True when the state changed since ``before`` beyond the tolerances (the base may move a cell)."""
        if before.holding != now.holding or math.dist(before.base, now.base) > base_tolerance + 1e-9:
            return True
        moved = any(
            math.dist(before.objects[k][:2], now.objects.get(k, before.objects[k])[:2]) > self.item_tolerance
            for k in before.objects
        )
        return moved or any(
            math.dist(before.clutter[k], now.clutter.get(k, before.clutter[k])) > self.item_tolerance
            for k in before.clutter
        )

    def _plan(self, scenario: Scenario, world: WorldState) -> tuple[Plan, float]:
        from expert.planner import plan

        started = time.perf_counter()
        result = plan(
            scenario, time_limit=self.time_limit, lattice=self.lattice, holding=world.holding, **self.planner_options
        )
        return result, time.perf_counter() - started

    def _fallback(self, world: WorldState) -> Action:
        """A move to the lattice point nearest the base, keeping the heading: the do-nothing action."""
        return Action(self.lattice.index(world.base), world.heading, 0, Mode.MOVE)

    def _count(self, **changes: Any) -> None:
        values = self._stats.to_dict()
        for key, value in changes.items():
            values[key] = value if key.startswith("last_") else values[key] + value
        self._stats = ExpertStats(**values)


def _solved(scenario: Scenario, world: WorldState) -> bool:
    """Every object delivered and the hand empty."""
    return world.holding is None and len(world.delivered(scenario)) == len(scenario.objects)


def _env_attribute(env: Any, name: str) -> Any:
    """``env.<name>`` through wrappers, or from the first env of a ``VecEnv``."""
    if env is None:
        raise ValueError(f"ExpertPolicy needs an env or an explicit {name}=")
    if hasattr(env, "get_wrapper_attr"):
        return env.get_wrapper_attr(name)
    if hasattr(env, "get_attr"):
        return env.get_attr(name, indices=[0])[0]
    return getattr(env, name)
