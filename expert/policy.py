"""The MILP expert as a policy: stable-baselines3's ``predict`` protocol over the env's observation.

:class:`ExpertPolicy` plans from the observation alone: the observation holds the whole
geometry (``fetchcarry_env.observation.decode`` rebuilds the scenario and the state), so
the expert can label any state: the start, mid-episode with an object in the hand,
after a push that slid differently in physics, or a state a learner drove into. This
is what DAgger needs.

It keeps its plan while execution follows it. After each action it expects the state
of the plan's next phase, and it replans when the observed state departs from that
beyond a tolerance (the base more than ``base_tolerance`` from the planned point,
another object in the hand, an object or a piece of clutter more than
``item_tolerance`` from where the plan put it: a push that slid, a move that stopped
at a contact), when the plan is used up before the task is done, and at
``episode_start``.

Before it gives an action, the expert checks it with the environment's own rules
(:func:`fetchcarry_env.rules.check_action`, pure geometry, no simulator). The MILP does
not model one of them: when several objects (or pieces of clutter) lie within the arm's
reach, the env picks (or pushes) the one nearest the middle of the posture's ranges.
When the env would refuse the planned action or act on another item, the expert first
replans if its plan is older than this state, then *repairs* the action: it moves the
acting base to the nearest lattice point (within ``REPAIR_RADIUS_CELLS``) from which the
env acts on the planned item, and replans after the repaired action. When no nearby base
works (the item the env would take stands right in front of the target), it plans again
with the confusing item made a small obstacle, so that the plan comes from another side,
and follows that plan up to the action on the target.

When it cannot act (the planner finds no plan, or no repair exists) the policy returns
the idle action (a ``move`` to the lattice point nearest the base, keeping the heading:
it does nothing useful and breaks nothing), says why in :attr:`ExpertPolicy.last_decision`
(``failure``), and does not plan again until the state changes.
:attr:`ExpertPolicy.stats` counts plans, replans, repairs, failures and planning seconds.

The policy uses the env only for its lattice and observation capacity (never its
simulation), so it works on a plain env, a wrapped env or an SB3 ``VecEnv``.
"""

from __future__ import annotations

import math
import time
from dataclasses import asdict, dataclass, field, replace
from typing import Any

import numpy as np

from expert.milp.grid import point_in_region
from expert.plans import Phase, Plan
from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.geometry import HEADINGS, Rect, heading_of
from fetchcarry_env.kinematics import push_headings
from fetchcarry_env.observation import Capacity, WorldState, decode
from fetchcarry_env.rules import Phase as EnvPhase
from fetchcarry_env.rules import check_action, move_stop
from fetchcarry_env.scenario import Obstacle, Scenario

DEFAULT_TIME_LIMIT = 10.0  # seconds per planning call, model building included
BASE_TOLERANCE = 0.01  # metres: the base is where the plan put it
ITEM_TOLERANCE = 0.02  # metres: an object or a piece of clutter is where the plan put it
REPAIR_RADIUS_CELLS = 3  # lattice cells: how far a repair may move the acting base from the planned one
ESCAPE_RADIUS_CELLS = 4  # lattice cells: how far an escape from a corner gap may go
MAX_CONFUSERS = 3  # items made blockers, one after the other, when planning around a confused pick or push


@dataclass(frozen=True)
class ExpertStats:
    """What the expert did since its last :meth:`ExpertPolicy.reset` (all envs of a batch together)."""

    plans: int = 0  # planning calls
    replans: int = 0  # planning calls other than the first of an episode
    failures: int = 0  # planning calls that found no plan (infeasible, time limit)
    repairs: int = 0  # actions adapted to the env: moved so that it acts on the planned item, or an escape move
    stuck: int = 0  # planned actions the env would refuse and no repair could fix
    fallbacks: int = 0  # idle actions returned because the expert could not act
    planning_s: float = 0.0  # seconds spent in the planner
    last_status: str | None = None  # status of the last planning call
    last_objective: float | None = None  # objective (Eq. 1) of the last plan found

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)


@dataclass(frozen=True)
class Decision:
    """What one ``predict`` call did for one env."""

    planned: bool  # the planner ran (once or twice)
    replanned: bool  # it ran although the episode was already under way
    reason: str  # why it planned, or "following", "done", "failed here"
    planning_s: float = 0.0  # seconds spent in the planner
    status: str | None = None  # the last plan's status when it planned, else None
    objective: float | None = None  # that plan's objective (Eq. 1), if one was found
    repaired: bool = False  # the action was moved to another base (see the module docstring)
    failure: str | None = None  # why the expert cannot act (the action is the idle one), else None

    @property
    def fallback(self) -> bool:
        """True when the action is the idle fallback because the expert could not act."""
        return self.failure is not None


@dataclass(frozen=True)
class _Step:
    """One action of the plan and the phase the world should be in after it."""

    action: Action
    expected: Phase


@dataclass
class _Track:
    """The plan being followed in one env of the batch."""

    steps: list[_Step] = field(default_factory=list)  # actions not yet given
    now: Phase | None = None  # the phase the world should be in now
    started: bool = False  # the planner already ran in this episode
    replan: str | None = None  # a reason to replan at the next call, whatever the state
    failed_in: WorldState | None = None  # the state in which the expert could not act
    failure: str | None = None  # why


@dataclass(frozen=True)
class _Planned:
    """The outcome of one planning call."""

    plan: Plan
    seconds: float
    replanned: bool


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
        self.lattice: Lattice = lattice if lattice is not None else _env_attribute(env, "lattice")
        self.capacity: Capacity = capacity if capacity is not None else _env_attribute(env, "capacity")
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
        observation: dict[str, np.ndarray] | np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | bool | None = None,
        deterministic: bool = True,
    ) -> tuple[np.ndarray, Any]:
        """The expert's action for each observation: ``(action, state)`` as stable-baselines3 returns them.

        ``observation`` is one observation dict (arrays of the env's shapes) or a batch
        (the same keys, arrays with a leading dimension, as a ``VecEnv`` gives them).
        ``episode_start`` (one bool per env) makes the expert drop its plan for that env.
        The expert is deterministic; ``deterministic`` is accepted for the protocol.
        ``state`` is returned unchanged.
        """
        flat = np.asarray(observation["observation"] if isinstance(observation, dict) else observation)
        batched = flat.ndim == 2
        rows = flat if batched else flat[None, :]
        starts = np.broadcast_to(np.asarray(False if episode_start is None else episode_start, dtype=bool), len(rows))
        while len(self._tracks) < len(rows):
            self._tracks.append(_Track())
        actions, decisions = [], []
        for k, row in enumerate(rows):
            if starts[k]:
                self._tracks[k] = _Track()
            action, decision = self._act(self._tracks[k], row)
            actions.append(action.to_array())
            decisions.append(decision)
        self.last_decisions = decisions
        stacked = np.stack(actions)
        return (stacked if batched else stacked[0]), state

    # -- one env -----------------------------------------------------------------------------

    def _act(self, track: _Track, row: np.ndarray) -> tuple[Action, Decision]:
        scenario, world = decode(row, self.capacity)
        if track.failed_in is not None:
            if _gap(track.failed_in, world, self.lattice.resolution, self.item_tolerance) is None:
                self._count(fallbacks=1)
                return self._idle(world), Decision(False, False, "failed here", failure=track.failure)
            track.failed_in = track.failure = None
        if _solved(scenario, world):
            return self._idle(world), Decision(False, False, "done")
        decision = self._prepare(track, scenario, world)
        if decision.failure is not None:
            track.steps, track.now, track.failed_in, track.failure = [], None, world, decision.failure
            self._count(fallbacks=1)
            return self._idle(world), decision
        step = track.steps.pop(0)
        track.now = step.expected
        return step.action, decision

    def _prepare(self, track: _Track, scenario: Scenario, world: WorldState) -> Decision:
        """Make the track's first step one the env executes as planned (plan, replan, repair); say what was done."""
        reason = self._why_plan(track, world)
        if reason is not None and (corner := _corner_gap(scenario, world)) is not None:
            return self._escape(track, scenario, world, reason, corner)
        planned: list[_Planned] = []
        if reason is not None:
            planned.append(self._plan_into(track, scenario, world))
        refusal = self._refusal(scenario, world, track.steps[0]) if track.steps else None
        if refusal is not None and not planned:  # the plan is older than this state: plan again first
            reason = f"refused: {refusal}"
            planned.append(self._plan_into(track, scenario, world))
            refusal = self._refusal(scenario, world, track.steps[0]) if track.steps else None
        made = _summary(planned, reason or "following")
        if planned and not planned[-1].plan.found:
            self._count(failures=1)
            return Decision(**made, failure=f"no plan ({planned[-1].plan.status})")
        if not track.steps:
            return Decision(**made, failure="the plan has no step from this state")
        if refusal is None:
            return Decision(**made)
        if self._repair(track, scenario, world):
            self._count(repairs=1)
            return Decision(**made, repaired=True)
        around = self._plan_around(track, scenario, world)
        if around:
            self._count(repairs=1)
            made = _summary(planned + around, f"{made['reason']}; planned around it")
            return Decision(**made, repaired=True)
        self._count(stuck=1)
        return Decision(
            **made, failure=f"stuck: the env would refuse the planned action ({refusal}) and no repair works"
        )

    def _why_plan(self, track: _Track, world: WorldState) -> str | None:
        """Why the expert must plan now, or ``None`` to follow its plan."""
        if track.now is None:
            return "retry after a failure" if track.started else "episode_start"
        departure = _gap(track.now, world, self.base_tolerance, self.item_tolerance)
        if departure is not None:
            return f"departed: {departure}"
        if track.replan is not None:
            return track.replan
        if not track.steps:
            return "plan used up"
        return None

    def _plan_into(
        self, track: _Track, scenario: Scenario, world: WorldState, problem: Scenario | None = None
    ) -> _Planned:
        """Plan from ``world`` and make the result the track's plan (an empty one if none was found).

        ``problem`` is the scenario handed to the planner when it is not ``scenario`` itself
        (see :meth:`_plan_around`).
        """
        from expert.planner import plan
        from expert.to_actions import plan_to_actions

        replanned = track.started
        started = time.perf_counter()
        result = plan(
            problem or scenario,
            time_limit=self.time_limit,
            lattice=self.lattice,
            holding=world.holding,
            **self.planner_options,
        )
        seconds = time.perf_counter() - started
        self._count(plans=1, replans=int(replanned), planning_s=seconds, last_status=result.status)
        track.started, track.replan, track.steps, track.now = True, None, [], None
        if result.found:
            self.last_plan = result
            self._count(last_objective=result.objective)
            actions = plan_to_actions(result, problem or scenario, self.lattice)
            track.steps = [_Step(a, p) for a, p in zip(actions, result.phases[1:], strict=True)]
            track.now = result.phases[0]
        return _Planned(result, seconds, replanned)

    def _plan_around(self, track: _Track, scenario: Scenario, world: WorldState) -> list[_Planned]:
        """Plan the track's first (confused) step again with the items the env confuses made blockers.

        The MILP does not know that the env picks (or pushes) the item nearest the middle
        of the posture's ranges. When the env would act on another item than the planned
        one and no nearby base helps, the expert plans on a copy of the scenario in which
        each confusing item is a small obstacle (the arm may not reach across it, Eq. 19),
        so the plan approaches the target from another side. It keeps that plan up to the
        action on the target (moves, then that action), checks the action against the real
        scenario and repairs it if the env would still confuse it (:meth:`_repair_arm`,
        :meth:`_repair_push` at the base the moves lead to), and plans as usual after it.
        Returns the planning calls made; empty when no such plan exists (the track is then
        left without steps).
        """
        step = track.steps[0]
        target = step.expected.target
        problem = scenario
        planned: list[_Planned] = []
        confused = self._confuser(scenario, world, step)
        blockers: set[str] = set()
        for _ in range(MAX_CONFUSERS):
            if not confused or confused == target or confused in blockers:
                break
            blockers.add(confused)
            problem = _as_obstacle(problem, confused)
            planned.append(self._plan_into(track, scenario, world, problem))
            steps = _until_acting_on(track.steps, target)
            if not steps or any(s.action.mode != Mode.MOVE for s in steps[:-1]):
                break
            steps, confused = self._settle_acting_step(scenario, world, steps)
            if confused is None:
                track.steps, track.replan = steps, None
                return planned
        track.steps, track.now = [], None
        return []

    def _confuser(self, scenario: Scenario, world: WorldState, step: _Step) -> str | None:
        """The item the env would act on instead of ``step``'s target ("" when it would refuse), or None."""
        outcome = check_action(scenario, world, self.lattice, step.action)
        if isinstance(outcome, str):
            return ""
        return None if outcome.target == step.expected.target else outcome.target

    def _settle_acting_step(
        self, scenario: Scenario, world: WorldState, steps: list[_Step]
    ) -> tuple[list[_Step], str | None]:
        """``steps`` (moves, then an action on the target) with the last one repaired if the env would confuse it.

        Returns the steps and what the env would still act on instead of the target ("" if
        it would refuse the action, None when the steps work).
        """
        for step in steps[:-1]:
            world = replace(world, base=step.expected.base, heading=step.expected.heading)
        confused = self._confuser(scenario, world, steps[-1])
        if confused is None:
            return steps, None
        last = steps[-1]
        if last.action.mode == Mode.PUSH:
            repaired = self._repair_push(scenario, world, last)
        else:
            repaired = self._repair_arm(scenario, world, last)
        if repaired is None:
            return steps, confused
        return [*steps[:-1], *repaired], None

    # -- checking actions with the env's rules --------------------------------------------------

    def _refusal(self, scenario: Scenario, world: WorldState, step: _Step) -> str | None:
        """Why the env would not do what ``step`` plans from ``world`` (refuse it, or act on another item)."""
        if step.action.mode == Mode.MOVE:
            return None
        outcome = check_action(scenario, world, self.lattice, step.action)
        return _mismatch(outcome, step)

    def _repair(self, track: _Track, scenario: Scenario, world: WorldState) -> bool:
        """Replace the track's first step by the nearest variant the env executes as planned, and replan after it.

        Pick and place: another lattice point for the base (reached without a contact),
        any heading and posture. Push: a move to another start first, then the same stroke
        from there. Returns False when nothing within ``REPAIR_RADIUS_CELLS`` works.
        """
        step = track.steps[0]
        if step.action.mode == Mode.PUSH:
            repaired = self._repair_push(scenario, world, step)
        else:
            repaired = self._repair_arm(scenario, world, step)
        if repaired is None:
            return False
        track.steps = repaired
        track.replan = "after a repaired action"
        return True

    def _repair_arm(self, scenario: Scenario, world: WorldState, step: _Step) -> list[_Step] | None:
        mode = step.action.mode
        for cell in self._cells_around(step.action.cell):
            base = self.lattice.point(*cell)
            if move_stop(scenario, world.base, base)[1] is not None:
                continue
            for heading, posture in self._poses(step.action.heading, step.action.posture, HEADINGS):
                action = Action(cell, heading, posture, mode)
                if _mismatch(check_action(scenario, world, self.lattice, action), step) is None:
                    return [_Step(action, replace(step.expected, base=base, heading=heading))]
        return None

    def _repair_push(self, scenario: Scenario, world: WorldState, step: _Step) -> list[_Step] | None:
        start_cell = self.lattice.index(world.base)
        di, dj = step.action.cell[0] - start_cell[0], step.action.cell[1] - start_cell[1]
        direction = heading_of((di, dj))
        if direction is None:
            return None  # not an axis-aligned stroke: nothing to repair
        headings = push_headings(direction)
        for cell in self._cells_around(start_cell):
            start, end_cell = self.lattice.point(*cell), (cell[0] + di, cell[1] + dj)
            if not (0 <= end_cell[0] < self.lattice.shape[0] and 0 <= end_cell[1] < self.lattice.shape[1]):
                continue
            end = self.lattice.point(*end_cell)
            if move_stop(scenario, world.base, start)[1] is not None or move_stop(scenario, start, end)[1] is not None:
                continue
            moved = replace(world, base=start)
            for heading, posture in self._poses(step.action.heading, step.action.posture, headings):
                action = Action(end_cell, heading, posture, Mode.PUSH)
                if _mismatch(check_action(scenario, moved, self.lattice, action), step) is None:
                    approach = Action(cell, heading, 0, Mode.MOVE)
                    before = Phase(start, heading, "move", holding=None, objects=dict(step.expected.objects))
                    return [_Step(approach, before), _Step(action, replace(step.expected, base=end, heading=heading))]
        return None

    def _escape(self, track: _Track, scenario: Scenario, world: WorldState, reason: str, corner: str) -> Decision:
        """Leave a corner gap with one straight move to the nearest lattice point outside every grown square.

        The MILP keeps the base out of every table and obstacle grown by the radius into a
        square (the paper's Eq. 18), which is stricter than the disc: a base that stopped at
        a contact near a corner can stand where the MILP has no plan from.
        """
        why = f"escape: the base is in the corner gap of {corner!r} ({reason})"
        for cell in self._cells_around(self.lattice.index(world.base), ESCAPE_RADIUS_CELLS):
            base = self.lattice.point(*cell)
            if (
                scenario.area.contains_disc(base, scenario.robot.radius)
                and _corner_gap(scenario, replace(world, base=base)) is None
                and move_stop(scenario, world.base, base)[1] is None
            ):
                objects = {k: v[:2] for k, v in world.objects.items()}
                expected = Phase(base, world.heading, "move", holding=world.holding, objects=objects)
                track.steps = [_Step(Action(cell, world.heading, 0, Mode.MOVE), expected)]
                track.replan = "after an escape move"
                self._count(repairs=1)
                return Decision(False, False, why, repaired=True)
        self._count(stuck=1)
        return Decision(False, False, why, failure=f"stuck: no straight move takes the base out of {corner!r}'s corner")

    def _cells_around(self, cell: tuple[int, int], r: int = REPAIR_RADIUS_CELLS) -> list[tuple[int, int]]:
        """Lattice points within ``r`` cells of ``cell``, nearest first (``cell`` itself first)."""
        nx, ny = self.lattice.shape
        around = [
            (cell[0] + i, cell[1] + j)
            for i in range(-r, r + 1)
            for j in range(-r, r + 1)
            if i * i + j * j <= r * r and 0 <= cell[0] + i < nx and 0 <= cell[1] + j < ny
        ]
        return sorted(around, key=lambda c: ((c[0] - cell[0]) ** 2 + (c[1] - cell[1]) ** 2, c))

    def _poses(self, heading: str, posture: int, headings: tuple[str, ...]) -> list[tuple[str, int]]:
        """Heading and posture pairs to try, the planned pair first."""
        pairs = [(h, p) for h in headings for p in range(self.capacity.postures)]
        return sorted(pairs, key=lambda pair: pair != (heading, posture))

    # -- helpers ------------------------------------------------------------------------------

    def _idle(self, world: WorldState) -> Action:
        """A move to the lattice point nearest the base, keeping the heading: the do-nothing action."""
        return Action(self.lattice.index(world.base), world.heading, 0, Mode.MOVE)

    def _count(self, **changes: Any) -> None:
        values = self._stats.to_dict()
        for key, value in changes.items():
            values[key] = value if key.startswith("last_") else values[key] + value
        self._stats = ExpertStats(**values)


def _summary(planned: list[_Planned], reason: str) -> dict[str, Any]:
    """The planning part of a :class:`Decision` from this call's planning calls."""
    return {
        "planned": bool(planned),
        "replanned": any(p.replanned for p in planned),
        "reason": reason,
        "planning_s": sum(p.seconds for p in planned),
        "status": planned[-1].plan.status if planned else None,
        "objective": planned[-1].plan.objective if planned else None,
    }


def _until_acting_on(steps: list[_Step], target: str | None) -> list[_Step]:
    """``steps`` up to and including the first pick or push of ``target`` (empty when there is none)."""
    for k, step in enumerate(steps):
        if step.action.mode in (Mode.PICK, Mode.PUSH) and step.expected.target == target:
            return steps[: k + 1]
    return []


def _as_obstacle(scenario: Scenario, item_id: str) -> Scenario:
    """``scenario`` with the object or piece of clutter ``item_id`` turned into an obstacle of its footprint."""
    objects = tuple(o for o in scenario.objects if o.id != item_id)
    clutter = tuple(c for c in scenario.clutter if c.id != item_id)
    if len(objects) < len(scenario.objects):
        obj = scenario.object(item_id)
        rect = Rect.around(obj.start, obj.radius, obj.radius)
    else:
        rect = scenario.clutter_item(item_id).rect
    obstacles = (*scenario.obstacles, Obstacle(f"{item_id}_as_blocker", rect))
    return replace(scenario, objects=objects, clutter=clutter, obstacles=obstacles)


def _mismatch(outcome: EnvPhase | str, step: _Step) -> str | None:
    """Why the env's resolution of an action (``check_action``) is not what ``step`` plans, or None."""
    if isinstance(outcome, str):
        return outcome
    planned = step.expected.target
    if outcome.target != planned:
        return f"the env would {outcome.mode.name.lower()} {outcome.target!r}, not {planned!r}"
    return None


def _gap(expected: Phase | WorldState, world: WorldState, base_tolerance: float, item_tolerance: float) -> str | None:
    """How ``world`` departs from ``expected`` beyond the tolerances (metres), or None."""
    gap = math.dist(expected.base, world.base)
    if gap > base_tolerance + 1e-9:
        return f"base {gap * 100:.1f} cm from the plan"
    if expected.holding != world.holding:
        return f"holding {world.holding} instead of {expected.holding}"
    for planned, seen in ((expected.objects, world.objects), (expected.clutter, world.clutter)):
        for item, position in planned.items():
            if item == world.holding or item not in seen:
                continue
            gap = math.dist(position[:2], seen[item][:2])
            if gap > item_tolerance:
                return f"{item} {gap * 100:.1f} cm from the plan"
    return None


def _corner_gap(scenario: Scenario, world: WorldState) -> str | None:
    """The id of a table or obstacle whose square grown by the radius holds the base (the MILP's Eq. 18), or None."""
    radius = scenario.robot.radius
    for item in (*scenario.tables, *scenario.obstacles):
        if not any(point_in_region(world.base, item.rect, radius, region) for region in range(4)):
            return item.id
    return None


def _solved(scenario: Scenario, world: WorldState) -> bool:
    """Every object delivered and the hand empty."""
    return world.holding is None and len(world.delivered(scenario)) == len(scenario.objects)


def _env_attribute(env: Any, name: str) -> Any:
    """``env.<name>`` through wrappers, or from the first env of a vector env (Gymnasium's or SB3's)."""
    if env is None:
        raise ValueError(f"ExpertPolicy needs an env or an explicit {name}=")
    if hasattr(env, "get_attr"):  # gymnasium.vector.VectorEnv and SB3's VecEnv: one value per env
        return env.get_attr(name)[0]
    if hasattr(env, "get_wrapper_attr"):
        return env.get_wrapper_attr(name)
    return getattr(env, name)
