"""The MILP expert as a policy: stable-baselines3's ``predict`` protocol over the env's observation.

:class:`ExpertPolicy` plans from the observation alone: the observation holds the whole
geometry (``fetchcarry_env.observation.decode`` rebuilds the scenario and the state), so
the expert can label any state: the start, mid-episode with an object in the hand,
after a push that slid differently in physics, or a state a learner drove into. This
is what DAgger needs.

It keeps its plan while execution follows it (:class:`expert.tracking.Track`). After
each action it expects the state of the plan's next phase, and it replans when the
observed state departs from that beyond a tolerance (the base more than
``base_tolerance`` from the planned point, another object in the hand, an object or a
piece of clutter more than ``item_tolerance`` from where the plan put it: a push that
slid, a move that stopped at a contact), when the plan is used up before the task is
done, and at ``episode_start``.

The planner models every rule the env applies, which object a pick takes and which
piece a push moves included, so every planned action executes as planned. Before it
gives an action the expert still checks it with the env's own rules
(:func:`fetchcarry_env.rules.check_action`, pure geometry, no simulator): when the env
would refuse it or act on another item (the world drifted within the tolerances), the
expert plans again from this state; if the fresh plan's action is refused too, it is
stuck. A base that stopped in a corner gap the MILP cannot plan from first moves out of
it (:mod:`expert.escape`).

When a planning call ends without a plan (status ``time_limit``: its node budget, or the
safety stop of ``time_limit`` seconds, came before a plan; the whole problem's bounds alone
can outlast it from seven or eight objects, and in an apartment), the expert makes the
decoupled plan of :func:`expert.decoupled.fallback_plan` (one object at a time, in the
order of fewest moves between deliveries: the long legs by the fewest straight moves the
env's move rule allows, :mod:`expert.approach`, the rest by single-object MILPs, each
within its node budget; ``fallback_time_limit``
seconds is its safety stop), and follows it: a valid plan, status ``feasible``, never
claimed optimal; it replans in closed loop as after any plan. Every budget is counted, so
the expert's episodes are the same at any load unless a safety stop decided (the plan's
``stats["clock_stopped"]`` says so).

When it cannot act (the planner and the fallback find no plan, or the env would refuse a fresh plan's
action) the policy returns the idle action (a ``move`` to the lattice point nearest the
base, keeping the heading: it does nothing useful and breaks nothing), says why in
:attr:`ExpertPolicy.last_decision` (``failure``), and does not plan again until the state
changes. :attr:`ExpertPolicy.stats` counts plans, replans, escapes, failures and
planning seconds.

The policy uses the env only for its lattice and observation capacity (never its
simulation), so it works on a plain env, a wrapped env or an SB3 ``VecEnv``.

It acts in the env it was given. On ``FetchCarryPush-v0`` it answers the env's
``MultiDiscrete`` phase actions, its plan's own. On ``FetchCarryPushPhases-v0`` (a
``Discrete`` action space) it answers the candidate index that stands for its plan's
action (:mod:`expert.candidates`: a move no candidate stands for is projected onto the
nearest allowed move and the expert replans from where the base ends;
:attr:`ExpertPolicy.projected` counts them), one env at a time: a vector env of phases
envs is refused. ``interface="env"`` keeps the plan's env actions on a phases env, for a
caller that labels or executes them itself (the phases env's ``index_of`` and
``step_env_action``). ``training.policies.phase_expert.PhaseExpert`` (the benchmark's
``expert-phases``) is this policy on a phases env.
"""

from __future__ import annotations

import time
from collections.abc import Hashable
from dataclasses import asdict, dataclass, replace
from typing import Any

import numpy as np

from expert import planner
from expert.candidates import NEAREST_RULES, UNEXPRESSIBLE, acts_in_candidates, candidate_answer
from expert.decoupled import fallback_plan
from expert.escape import corner_gap, escape_move
from expert.milp.deadline import Deadline, TimeUp
from expert.plans import Plan
from expert.tracking import PlannedAction, Track, departure, on_lattice, solved
from fetchcarry_env.actions import Action, Lattice, Mode
from fetchcarry_env.observation import Capacity, WorldState, decode
from fetchcarry_env.rules import check_action
from fetchcarry_env.scenario import Scenario

DEFAULT_TIME_LIMIT = 10.0  # seconds per planning call, model building included: the safety stop
DEFAULT_NODE_LIMIT = 20_000  # SCIP nodes per model of a planning call: the expert's counted budget
BASE_TOLERANCE = 0.01  # metres: the base is where the plan put it
ITEM_TOLERANCE = 0.02  # metres: an object or a piece of clutter is where the plan put it
FALLBACK_FACTOR = 3.0  # the decoupled fallback plan's safety stop, by default, per second of the planner's
INTERFACES = ("env", "phases")  # what the expert answers: env actions, or candidate indices of a phases env


@dataclass(frozen=True)
class ExpertStats:
    """What the expert did since its last :meth:`ExpertPolicy.reset` (all envs of a batch together)."""

    plans: int = 0  # planning calls
    replans: int = 0  # planning calls other than the first of an episode
    failures: int = 0  # planning calls that found no plan (infeasible, time limit), the fallback included
    decoupled: int = 0  # planning calls answered by the decoupled fallback plan (the planner's time ran out)
    repairs: int = 0  # actions the expert added to its plan: escape moves out of a corner gap
    stuck: int = 0  # freshly planned actions the env would refuse
    fallbacks: int = 0  # idle actions returned because the expert could not act
    planning_s: float = 0.0  # seconds spent in the planner (and the fallback plan)
    clock_stopped: int = 0  # planning calls whose answer the safety stop (the wall clock) decided: not reproducible
    last_status: str | None = None  # status of the last planning call
    last_objective: float | None = None  # objective (the task cost) of the last plan found

    def to_dict(self) -> dict[str, Any]:
        return asdict(self)

    def plus(self, **counts: float) -> ExpertStats:
        """These statistics with ``counts`` added to the counters of the same names."""
        return replace(self, **{name: getattr(self, name) + value for name, value in counts.items()})


@dataclass(frozen=True)
class Decision:
    """What one ``predict`` call did for one env."""

    planned: bool  # the planner ran (once or twice)
    replanned: bool  # it ran although the episode was already under way
    reason: str  # why it planned, or "following", "done", "failed here"
    planning_s: float = 0.0  # seconds spent in the planner
    status: str | None = None  # the last plan's status when it planned, else None
    objective: float | None = None  # that plan's objective (Eq. 1), if one was found
    repaired: bool = False  # the action is an escape move the plan did not have (see the module docstring)
    failure: str | None = None  # why the expert cannot act (the action is the idle one), else None

    @property
    def fallback(self) -> bool:
        """True when the action is the idle fallback because the expert could not act."""
        return self.failure is not None


@dataclass(frozen=True)
class _Planned:
    """The outcome of one planning call."""

    plan: Plan
    seconds: float
    replanned: bool


def clock_decided(result: Plan) -> bool:
    """Whether the safety stop (the wall clock) decided ``result``: the planner's call, the call a fallback
    answered, or the fallback itself (which a stop cut short)."""
    stats = result.stats
    return bool(
        stats.get("clock_stopped")
        or stats.get("planner", {}).get("clock_stopped")
        or stats.get("fallback") == "stopped by its time limit"
    )


class ExpertPolicy:
    """The MILP expert behind stable-baselines3's ``predict(observation, state, episode_start, deterministic)``.

    ``env`` is the env (wrapped or not) or a ``VecEnv`` whose observations it will see; its
    ``lattice`` and ``capacity`` fix how actions and observations are laid out (pass them
    explicitly to use the policy without an env). ``time_limit`` (seconds) is each planning
    call's safety stop; its counted budget is ``node_limit`` SCIP nodes per model (a planner
    option, ``DEFAULT_NODE_LIMIT`` by default). ``base_tolerance`` and ``item_tolerance`` (metres)
    say how far the state may drift from the plan before the expert replans.
    ``fallback_time_limit`` (seconds, default ``FALLBACK_FACTOR * time_limit``; 0 turns the
    fallback off) is the safety stop of the decoupled plan made when a planning call found no
    plan. ``interface`` is what it answers: ``"env"``
    (the env actions it plans in) or ``"phases"`` (the candidate index of a single
    ``FetchCarryPushPhases-v0`` env); None, the default: the env's own (``"phases"`` for a
    phases env). ``projection`` (``"end"`` or ``"detour"``) says which allowed move stands
    in for a move no candidate expresses (:func:`expert.candidates.nearest_move`).
    ``planner_options`` are fields of :class:`expert.planner.PlannerOptions`. ``ValueError`` for an
    interface the env cannot take (a vector env of phases envs answered in candidates).
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
        fallback_time_limit: float | None = None,
        interface: str | None = None,
        projection: str = "end",
        **planner_options: Any,
    ) -> None:
        if time_limit <= 0:
            raise ValueError(f"time_limit must be positive (seconds), got {time_limit}")
        if fallback_time_limit is not None and fallback_time_limit < 0:
            raise ValueError(f"fallback_time_limit must not be negative (seconds), got {fallback_time_limit}")
        if base_tolerance < 0 or item_tolerance < 0:
            raise ValueError("tolerances must not be negative")
        if projection not in NEAREST_RULES:
            raise ValueError(f"projection must be one of {', '.join(NEAREST_RULES)}, got {projection!r}")
        self.interface = _interface(env, interface)
        self.projection = projection
        self._phases_env = env if self.interface == "phases" else None
        self.lattice: Lattice = lattice if lattice is not None else _env_attribute(env, "lattice")
        self.capacity: Capacity = capacity if capacity is not None else _env_attribute(env, "capacity")
        self.time_limit = time_limit
        self.fallback_time_limit = FALLBACK_FACTOR * time_limit if fallback_time_limit is None else fallback_time_limit
        self.base_tolerance = base_tolerance
        self.item_tolerance = item_tolerance
        self.planner_options = planner.PlannerOptions(node_limit=DEFAULT_NODE_LIMIT).with_fields(**planner_options)
        self._tracks: list[Track] = []
        self._stats = ExpertStats()
        self.last_decisions: list[Decision] = []
        self.last_plan: Plan | None = None
        self.last_projected = False  # the last answer is a projected move (interface "phases")
        self.projected = 0  # moves projected onto their nearest candidate since the last reset
        self.unexpressible = 0  # other actions no allowed candidate expressed since the last reset
        self._left: tuple[Hashable, frozenset[tuple[int, int]]] | None = None  # (world, cells projected moves left)

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
        self.last_projected = False
        self.projected = self.unexpressible = 0
        self._left = None

    def predict(
        self,
        observation: dict[str, np.ndarray] | np.ndarray,
        state: Any = None,
        episode_start: np.ndarray | bool | None = None,
        deterministic: bool = True,
        action_masks: np.ndarray | None = None,
    ) -> tuple[np.ndarray, Any]:
        """The expert's action for each observation: ``(action, state)`` as stable-baselines3 returns them.

        ``observation`` is one observation dict (arrays of the env's shapes) or a batch
        (the same keys, arrays with a leading dimension, as a ``VecEnv`` gives them; in the
        ``phases`` interface a batch of one: the candidates are those of the env's state).
        ``episode_start`` (one bool per env) makes the expert drop its plan for that env.
        The expert is deterministic; ``deterministic`` is accepted for the protocol (the
        planner checks its actions with the env's own rules); ``action_masks``, if given,
        is the state's candidate mask in the ``phases`` interface (else the env's is read).
        ``state`` is returned unchanged.
        """
        flat = np.asarray(observation["observation"] if isinstance(observation, dict) else observation)
        batched = flat.ndim == 2
        rows = flat if batched else flat[None, :]
        if self._phases_env is not None and len(rows) != 1:
            raise ValueError(f"in the phases interface the expert answers one observation at a time, got {len(rows)}")
        starts = np.broadcast_to(np.asarray(False if episode_start is None else episode_start, dtype=bool), len(rows))
        while len(self._tracks) < len(rows):
            self._tracks.append(Track())
        actions, decisions = [], []
        for k, row in enumerate(rows):
            if starts[k]:
                self._tracks[k] = Track()
                self._left = None
            scenario, world = on_lattice(*decode(row, self.capacity), self.lattice)
            action, decision = self._act(self._tracks[k], scenario, world)
            answer = action.to_array()
            if self._phases_env is not None:
                answer, decision = self._candidate(answer, decision, action_masks, scenario, world)
            actions.append(answer)
            decisions.append(decision)
        self.last_decisions = decisions
        stacked = np.stack(actions)
        return (stacked if batched else stacked[0]), state

    def _candidate(
        self, action: np.ndarray, decision: Decision, action_masks: np.ndarray | None, scenario: Scenario,
        world: WorldState,
    ) -> tuple[np.int64, Decision]:  # fmt: skip
        """The phases env's candidate for the env ``action`` (:func:`expert.candidates.candidate_answer`).

        A projected move avoids the cells that projected moves left since the last other
        answer in the same world (objects, clutter and the hand as they are; the base apart).
        """
        same = (scenario.name, world.holding, _rounded(world.objects, world.holding), _rounded(world.clutter, None))
        here = self.lattice.index(world.base)
        left = self._left[1] if self._left is not None and self._left[0] == same else frozenset()
        answer = candidate_answer(
            self._phases_env, action, project=decision.failure is None, rule=self.projection, mask=action_masks,
            avoid=left | {here},
        )  # fmt: skip
        self._left = (same, left | {here}) if answer.projected else None
        self.last_projected = answer.projected
        if answer.projected:
            self.projected += 1
            decision = replace(decision, reason=f"{decision.reason}; move projected onto candidate {answer.index}")
        elif answer.unexpressible is not None:
            self.unexpressible += 1
            reason = answer.unexpressible
            decision = replace(decision, reason=reason, status=UNEXPRESSIBLE, failure=reason, repaired=False)
        return np.int64(answer.index), decision

    # -- one env -----------------------------------------------------------------------------

    def _act(self, track: Track, scenario: Scenario, world: WorldState) -> tuple[Action, Decision]:
        if track.failed_in is not None:
            if departure(track.failed_in, world, self.lattice.resolution, self.item_tolerance) is None:
                self._stats = self._stats.plus(fallbacks=1)
                return self._idle(world), Decision(False, False, "failed here", failure=track.failure)
            track.failed_in = track.failure = None
        if solved(scenario, world):
            return self._idle(world), Decision(False, False, "done")
        decision = self._prepare(track, scenario, world)
        if decision.failure is not None:
            track.fail(world, decision.failure)
            self._stats = self._stats.plus(fallbacks=1)
            return self._idle(world), decision
        return track.advance(), decision

    def _prepare(self, track: Track, scenario: Scenario, world: WorldState) -> Decision:
        """Make the track's first step one the env executes as planned (plan or replan); say what was done."""
        reason = track.why_plan(world, self.base_tolerance, self.item_tolerance)
        if reason is not None and (corner := corner_gap(scenario, world)) is not None:
            return self._escape(track, scenario, world, corner, reason)
        planned: list[_Planned] = []
        if reason is not None:
            planned.append(self._plan(track, scenario, world))
        refusal = self._refusal(scenario, world, track.steps[0]) if track.steps else None
        if refusal is not None and not planned:  # the world drifted within the tolerances: plan from here
            reason = f"refused: {refusal}"
            planned.append(self._plan(track, scenario, world))
            refusal = self._refusal(scenario, world, track.steps[0]) if track.steps else None
        made = _summary(planned, reason or "following")
        if planned and not planned[-1].plan.found:
            return Decision(**made, failure=f"no plan ({planned[-1].plan.status})")
        if not track.steps:
            return Decision(**made, failure="the plan has no step from this state")
        if refusal is not None:
            self._stats = self._stats.plus(stuck=1)
            return Decision(**made, failure=f"stuck: the env would refuse the planned action ({refusal})")
        return Decision(**made)

    def _plan(self, track: Track, scenario: Scenario, world: WorldState) -> _Planned:
        """Plan from ``world`` and make the result the track's plan (an empty one if none was found)."""
        replanned = track.started
        started = time.perf_counter()
        options = self.planner_options
        result = planner.plan(
            scenario, time_limit=self.time_limit, lattice=self.lattice, holding=world.holding, options=options
        )
        decoupled = result.status == "time_limit" and self.fallback_time_limit > 0
        if decoupled:
            result = self._fallback(scenario, world, result)
        seconds = time.perf_counter() - started
        self._stats = self._stats.plus(
            plans=1,
            replans=int(replanned),
            failures=int(not result.found),
            decoupled=int(decoupled and result.found),
            planning_s=seconds,
            clock_stopped=int(clock_decided(result)),
        )
        self._stats = replace(self._stats, last_status=result.status)
        if result.found:
            self.last_plan = result
            self._stats = replace(self._stats, last_objective=result.objective)
        track.follow(result, scenario, self.lattice)
        return _Planned(result, seconds, replanned)

    def _fallback(self, scenario: Scenario, world: WorldState, timed_out: Plan) -> Plan:
        """The decoupled plan (:func:`expert.decoupled.fallback_plan`) after a call that found no plan.

        Its stats keep the call's under ``stats["planner"]``; without a plan the answer is the
        call's status (``time_limit``) with both stats.
        """
        delivered = set(world.delivered(scenario))
        order = [o.id for o in scenario.objects if o.id not in delivered or o.id == world.holding]
        sub_planner = planner.SubPlanner(self.planner_options, Deadline.after(self.fallback_time_limit), self.lattice)
        try:
            result = fallback_plan(scenario, order, self.lattice, sub_planner, holding=world.holding)
        except TimeUp:  # its safety stop came first
            return replace(timed_out, stats={**timed_out.stats, "fallback": "stopped by its time limit"})
        stats = {**result.stats, "planner": timed_out.stats}
        if not result.found:
            return replace(timed_out, stats=stats)
        return replace(result, stats=stats)

    def _escape(self, track: Track, scenario: Scenario, world: WorldState, corner: str, reason: str) -> Decision:
        """Leave the corner gap of ``corner`` with one straight move (:mod:`expert.escape`), then plan."""
        why = f"escape: the base is in the corner gap of {corner!r} ({reason})"
        step = escape_move(scenario, world, self.lattice)
        if step is None:
            self._stats = self._stats.plus(stuck=1)
            failure = f"stuck: no straight move takes the base out of {corner!r}'s corner"
            return Decision(False, False, why, failure=failure)
        track.steps, track.replan = [step], "after an escape move"
        self._stats = self._stats.plus(repairs=1)
        return Decision(False, False, why, repaired=True)

    def _refusal(self, scenario: Scenario, world: WorldState, step: PlannedAction) -> str | None:
        """Why the env would not do what ``step`` plans from ``world`` (refuse it, or act on another item)."""
        if step.action.mode == Mode.MOVE:
            return None
        outcome = check_action(scenario, world, self.lattice, step.action)
        if isinstance(outcome, str):
            return outcome
        if outcome.target != step.expected.target:
            return f"the env would {outcome.mode.name.lower()} {outcome.target!r}, not {step.expected.target!r}"
        return None

    def _idle(self, world: WorldState) -> Action:
        """A move to the lattice point nearest the base, keeping the heading: the do-nothing action."""
        return Action(self.lattice.index(world.base), world.heading, 0, Mode.MOVE)


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


def _rounded(places: dict[str, tuple[float, ...]], held: str | None) -> tuple:
    """``places`` to the millimetre, the held object's left out (it moves with the base), in a fixed order."""
    return tuple(sorted((key, tuple(round(v, 3) for v in p)) for key, p in places.items() if key != held))


def _interface(env: Any, asked: str | None) -> str:
    """What the expert answers on ``env`` (:data:`INTERFACES`): ``asked``, or by default the env's own."""
    if asked is not None and asked not in INTERFACES:
        raise ValueError(f"interface must be one of {', '.join(INTERFACES)} (or None: the env's), got {asked!r}")
    if asked == "env":
        return "env"
    candidates = env is not None and acts_in_candidates(env)
    if asked == "phases" and not candidates:
        raise ValueError(
            "interface='phases' answers candidate indices of a FetchCarryPushPhases-v0 env; "
            f"this env's actions are {getattr(env, 'action_space', None)}"
        )
    if candidates and hasattr(env, "get_attr"):  # a vector env: the candidates are each env's own
        raise ValueError(
            "ExpertPolicy answers candidate indices for one FetchCarryPushPhases-v0 env at a time; for a vector "
            'env give interface="env" (the env actions it plans in; each env\'s step_env_action executes them)'
        )
    return "phases" if candidates else "env"


def _env_attribute(env: Any, name: str) -> Any:
    """``env.<name>`` through wrappers, or from the first env of a vector env (Gymnasium's or SB3's)."""
    if env is None:
        raise ValueError(f"ExpertPolicy needs an env or an explicit {name}=")
    if hasattr(env, "get_attr"):  # gymnasium.vector.VectorEnv and SB3's VecEnv: one value per env
        return env.get_attr(name)[0]
    if hasattr(env, "get_wrapper_attr"):
        return env.get_wrapper_attr(name)
    return getattr(env, name)
