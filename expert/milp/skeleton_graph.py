"""The skeleton relaxation's graph, built once per problem: the lower bounds on phases, travel and Eq. 1 search it.

A state is ``(delivered, held, pushed, last action, its exit pose box)``: the objects
delivered, the one in the hand (or None), the covering pieces pushed, and the action
that led there with the box of lattice points where the base is at its end. An edge is
one more action done from one of its poses: it costs at least ``q`` phases and ``t``
metres of travel (:meth:`expert.milp.bounds.PairCosts.step`, lower bounds over the
boxes). Every action adds one to the actions done, so the graph is a DAG of levels and
every edge goes from one level to the next: a least cost is one pass over the levels
(:meth:`SkeletonGraph.least_from_start`), no priority queue.

Every plan maps onto a path of this graph, each of its phases' moves between poses at
least as long as the edge says, so the least cost of a path bounds every plan from below.
"""

from __future__ import annotations

import dataclasses
import functools
from collections.abc import Callable, Collection, Sequence
from dataclasses import dataclass
from itertools import pairwise

import numpy as np

from expert.milp.deadline import NEVER, Deadline
from expert.milp.grid import IndexBox
from expert.milp.problem import Problem

Key = tuple[str, str]  # (kind, target) of an arm action
Step = Callable[[IndexBox | None, str, IndexBox, IndexBox], tuple[int, float]]  # where, kind, entry, exit -> (q, t)
MAX_EDGES = 1 << 26  # the default budget of a skeleton graph: about 2 GB of edges, several times that while built


class GraphTooLarge(Exception):
    """Raised by :meth:`SkeletonGraph.build` before a level would take the graph past its budget of edges."""


def skeleton_moves(problem: Problem, delivered: frozenset, held: str | None, pushed: frozenset) -> list:
    """The actions possible from a skeleton state: ``((kind, target), (delivered, held, pushed) after)``."""
    moves = []
    if held is not None:
        if all(c in pushed for c in problem.covers.get(held, ())):
            moves.append((("place", held), (delivered | {held}, None, pushed)))
    else:
        for object_id in problem.deliver:
            if object_id not in delivered:
                moves.append((("pick", object_id), (delivered, object_id, pushed)))
    for clutter_id in problem.pushes.pushable:  # with an empty hand or holding an object
        if clutter_id not in pushed:
            moves.append((("push", clutter_id), (delivered, held, pushed | {clutter_id})))
    return moves


def all_done(problem: Problem, delivered: frozenset, pushed: frozenset) -> bool:
    """Whether a skeleton state has every object delivered and every covering piece pushed."""
    return len(delivered) == len(problem.deliver) and len(pushed) == len(problem.pushes.pushable)


def run_starts(values: np.ndarray) -> np.ndarray:
    """Where each run of equal consecutive ``values`` starts (the indices ``np.minimum.reduceat`` takes)."""
    return np.flatnonzero(np.r_[True, values[1:] != values[:-1]])


@dataclass(frozen=True)
class Layers:
    """A DAG whose nodes are numbered level by level and whose edges go from one level to the next.

    Edges are listed by level (their source's) and within a level by source, so a least
    cost from the start (node 0) or to the end is one pass over the levels.
    """

    level_starts: list[int]  # nodes of level L: level_starts[L] .. level_starts[L + 1] - 1
    edge_starts: list[int]  # edges out of level L: edge_starts[L] .. edge_starts[L + 1] - 1
    src: np.ndarray
    dst: np.ndarray

    @functools.cached_property
    def by_destination(self) -> np.ndarray:
        """The edges in order of level, and within a level by destination (stable): for minima per destination."""
        return np.concatenate(
            [e0 + np.argsort(self.dst[e0:e1], kind="stable") for e0, e1 in pairwise(self.edge_starts)]
            or [np.zeros(0, dtype=np.intp)]
        )

    def destinations(self, e0: int, e1: int) -> tuple[np.ndarray, np.ndarray]:
        """Of the edges ``e0 .. e1 - 1`` of one level in :attr:`by_destination` order: each destination once, and
        where its edges start in that order (for ``np.minimum.reduceat``)."""
        targets = self.dst[self.by_destination[e0:e1]]
        firsts = run_starts(targets)
        return targets[firsts], firsts

    def least_from_start(self, cost: np.ndarray, deadline: Deadline = NEVER) -> np.ndarray:
        """Per node, the least total ``cost`` (one value per edge) of a path from node 0; inf where none."""
        least = np.full(self.level_starts[-1], np.inf)
        least[0] = 0.0
        for e0, e1 in pairwise(self.edge_starts):
            if e1 > e0:
                deadline.check()
                order = self.by_destination[e0:e1]
                targets, firsts = self.destinations(e0, e1)
                least[targets] = np.minimum.reduceat(least[self.src[order]] + cost[order], firsts)
        return least

    def least_to_end(
        self, cost: np.ndarray, ends: np.ndarray, dead_end: float, deadline: Deadline = NEVER
    ) -> np.ndarray:
        """Per node, the least total ``cost`` of a path to a node of ``ends`` (0 there); ``dead_end`` at a node
        neither in ``ends`` nor with an edge out, and counted on through it."""
        least = np.where(ends, 0.0, dead_end)
        for level in range(len(self.edge_starts) - 2, -1, -1):
            e0, e1 = self.edge_starts[level], self.edge_starts[level + 1]
            if e1 > e0:
                deadline.check()
                sources = self.src[e0:e1]
                firsts = run_starts(sources)
                least[sources[firsts]] = np.minimum.reduceat(least[self.dst[e0:e1]] + cost[e0:e1], firsts)
        return least


@dataclass(frozen=True)
class ActionGraph(Layers):
    """The skeleton graph with its poses merged: a node per (delivered, held, pushed, last action).

    An edge costs at least ``q`` phases: the least over the pose pairs of the two actions.
    A node is four integer columns named by ``names`` (:class:`SkeletonGraph`'s first four).
    """

    q: np.ndarray
    names: Alphabet
    columns: dict[str, np.ndarray]  # delivered_set, held, pushed_set, last
    finished: np.ndarray

    @functools.cached_property
    def nodes(self) -> list[tuple]:
        """Per node ``(delivered, held, pushed, last action)``: frozensets of ids, an id, a key."""
        return [self.names.node(*row) for row in zip(*self.columns.values(), strict=True)]


@dataclass(frozen=True)
class Alphabet:
    """A problem's skeleton in integers: object ``i`` is bit ``1 << i`` of a set of delivered objects, piece ``c``
    bit ``1 << c`` of a set of pushed pieces, and the actions are numbered places, picks, pushes (the order
    :func:`skeleton_moves` lists them in, so one state's moves come in the order of their numbers)."""

    objects: tuple[str, ...]  # problem.deliver
    pieces: tuple[str, ...]  # problem.pushes.pushable
    keys: tuple[Key, ...]

    @classmethod
    def of(cls, problem: Problem) -> Alphabet:
        objects, pieces = tuple(problem.deliver), tuple(problem.pushes.pushable)
        keys = [("place", o) for o in objects] + [("pick", o) for o in objects] + [("push", c) for c in pieces]
        return cls(objects, pieces, tuple(keys))

    @property
    def dtype(self) -> type:
        """Of a set's bit mask: int64, or Python integers past 62 objects or pieces (a graph that large is never
        finished: the caller's deadline stops its search)."""
        return np.int64 if max(len(self.objects), len(self.pieces)) <= 62 else object

    def node(self, delivered: int, held: int, pushed: int, last: int) -> tuple:
        """``(delivered, held, pushed, last action)`` by name from the integers: frozensets of ids, an id, a key."""
        return (
            frozenset(o for i, o in enumerate(self.objects) if delivered >> i & 1),
            None if held < 0 else self.objects[held],
            frozenset(c for i, c in enumerate(self.pieces) if pushed >> i & 1),
            None if last < 0 else self.keys[last],
        )


@dataclass(frozen=True)
class SkeletonGraph(Layers):
    """The states (the nodes, in order of discovery) and the edges between them.

    ``src[e] -> dst[e]`` costs at least ``q[e]`` phases and ``t[e]`` metres of travel.
    A state is five integer columns named by :attr:`names`: ``delivered_set`` and
    ``pushed_set`` (bit masks), ``held`` (an object's number, -1: none), ``last`` (the number
    of the action that led there, -1 at the start) and ``exit`` (its exit box, ``boxes[exit]``).
    Per state also: ``finished`` (every object delivered, every covering piece pushed),
    ``delivered`` (how many objects), ``placed`` (its last action is a place),
    ``slot`` (the number of its last action and exit box in ``slots``; the start's is -1)
    and ``group`` (its node in :attr:`actions`, the graph without poses).
    """

    names: Alphabet
    delivered_set: np.ndarray
    held: np.ndarray
    pushed_set: np.ndarray
    last: np.ndarray
    exit: np.ndarray
    boxes: list[IndexBox | None]
    q: np.ndarray
    t: np.ndarray
    finished: np.ndarray
    delivered: np.ndarray
    placed: np.ndarray
    slot: np.ndarray
    slots: list[tuple[Key, IndexBox]]
    group: np.ndarray
    group_columns: dict[str, np.ndarray]  # the first four STATE_COLUMNS of each group, numbered level by level

    @classmethod
    def build(
        cls, problem: Problem, poses: dict[Key, tuple[tuple[IndexBox, IndexBox], ...]], step: Step,
        deadline: Deadline = NEVER, max_edges: int = MAX_EDGES,
    ) -> SkeletonGraph:  # fmt: skip
        """Every state reachable from the start; ``poses[action]`` lists its (entry, exit) boxes.

        Raises :class:`GraphTooLarge` rather than list more than ``max_edges`` edges (the
        states number up to ``2^objects`` times the poses: memory, not time, runs out first).

        One level at a time, in arrays: every move of every state of the level, then its new
        states numbered in order of discovery (by source, action and pose), as a search state
        by state would number them. The steps of an action from a box, which depend on
        nothing else, are listed once.
        """
        return _Builder(problem, poses, step, deadline, max_edges).graph()

    @property
    def state_count(self) -> int:
        return self.level_starts[-1]

    @functools.cached_property
    def states(self) -> list[tuple]:
        """Per state ``(delivered, held, pushed, last action, exit box)``: frozensets of ids, an id, a key, a box."""
        columns = (self.delivered_set, self.held, self.pushed_set, self.last)
        return [(*self.names.node(*row), self.boxes[x]) for *row, x in zip(*columns, self.exit, strict=True)]

    def within(self, n_phases: int) -> SkeletonGraph:
        """The graph without the edges of more than ``n_phases - 1`` phases (no plan of ``n_phases`` takes one).

        Its states are all kept: one reached only by such edges is reached by no plan, and
        every bound through it is ``inf``.
        """
        return self.keeping(self.q <= n_phases - 1)

    def in_order(self, order: Sequence[str], deliver: Collection[str]) -> SkeletonGraph:
        """The graph without the picks out of ``order``, as :func:`expert.milp.order.add_pick_order` restricts a model.

        Of ``order``'s objects the model delivers (``deliver``), each one after the first is
        picked only once the one before it is delivered; any other object at any time. The
        plans of the restricted model map onto this graph's paths, so its bounds hold for them.
        """
        chain = [target for target in order if target in deliver]
        delivered = np.zeros(self.state_count, dtype=self.names.dtype)  # per state, its delivered objects of the chain
        for position, target in enumerate(chain):
            if target in self.names.objects:
                delivered |= (self.delivered_set >> self.names.objects.index(target) & 1) << position
        needed = np.zeros(len(self.names.keys) + 1, dtype=self.names.dtype)  # per action (none: the last), chain before
        for position, after in enumerate(chain[1:]):  # the pick of ``after`` needs chain[position] delivered
            needed[self.names.keys.index(("pick", after))] = 1 << position
        need = needed[self.last][self.dst]  # what must be delivered before the action that led to an edge's end
        return self.keeping((need & delivered[self.src]) == need)

    def keeping(self, keep: np.ndarray) -> SkeletonGraph:
        """The graph with the edges where ``keep`` is True (its states all kept).

        Where this graph's :attr:`by_destination` is known, the new graph's is that order
        without the edges left out (the same stable order, no sort).
        """
        if keep.all():
            return self
        kept_before = np.concatenate(([0], np.cumsum(keep)))
        graph = dataclasses.replace(
            self,
            edge_starts=[int(kept_before[e]) for e in self.edge_starts],
            src=self.src[keep],
            dst=self.dst[keep],
            q=self.q[keep],
            t=self.t[keep],
        )
        if "by_destination" in self.__dict__:  # cached_property's store
            order = self.by_destination
            graph.__dict__["by_destination"] = kept_before[order[keep[order]]]
        return graph

    @functools.cached_property
    def actions(self) -> ActionGraph:
        """This graph with the states of one (delivered, held, pushed, last action) merged, each edge its least ``q``.

        A state's groups are numbered in order of discovery, so level by level, and every
        exit box of the last action is among a group's states (each action's poses all
        lead on from any state), so an edge's ``q`` is the least over both actions' poses.
        """
        count = len(self.group_columns["last"])
        pair = self.group[self.src] * count + self.group[self.dst]
        order = np.argsort(pair, kind="stable")
        firsts = run_starts(pair[order])
        src, dst = pair[order][firsts] // count, pair[order][firsts] % count
        levels = np.repeat(np.arange(len(self.level_starts) - 1), np.diff(self.level_starts))
        group_level = np.empty(count, dtype=np.intp)
        group_level[self.group] = levels
        level_starts = np.searchsorted(group_level, np.arange(len(self.level_starts))).tolist()
        edge_starts = np.searchsorted(group_level[src], np.arange(len(self.edge_starts))).tolist()
        finished = np.zeros(count, dtype=bool)
        finished[self.group] = self.finished
        return ActionGraph(
            level_starts, edge_starts, src, dst, np.minimum.reduceat(self.q[order], firsts), self.names,
            self.group_columns, finished,
        )  # fmt: skip


def _codes(columns: Sequence[tuple[np.ndarray, int]]) -> np.ndarray:
    """One integer per row that tells rows apart as their ``(values, radix)`` columns do (``0 <= values < radix``).

    The columns are combined in mixed radix; where the next product could pass 2^62, the
    code so far is first renumbered densely (``np.unique``), which keeps rows apart, and
    past that in Python integers (a column of more than 62 bits).
    """
    code = np.zeros(len(columns[0][0]), dtype=np.int64)
    size = 1
    for values, radix in columns:
        if code.dtype != object and size * radix >= 1 << 62:
            _, code = np.unique(code, return_inverse=True)
            size = int(code.max(initial=0)) + 1
            if size * radix >= 1 << 62:
                code = code.astype(object)
        code = code * radix + values
        size *= radix
    return code


def _bit_counts(masks: np.ndarray) -> np.ndarray:
    """The number of bits set in each mask."""
    if masks.dtype == object:
        return np.array([int(mask).bit_count() for mask in masks], dtype=np.intp)
    return np.bitwise_count(masks).astype(np.intp)


def _first_seen(codes: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Of ``codes``: the index of each distinct value's first row, in order of those rows, and per row the number
    of its value in that order."""
    _, firsts, inverse = np.unique(codes, return_index=True, return_inverse=True)
    by_first = np.argsort(firsts)
    number = np.empty(len(firsts), dtype=np.intp)
    number[by_first] = np.arange(len(firsts))
    return firsts[by_first], number[inverse]


STATE_COLUMNS = ("delivered_set", "held", "pushed_set", "last", "exit")  # SkeletonGraph's, of one state
CHUNK_EDGES = 1 << 20  # edges listed at a time when building the skeleton graph


@dataclass
class _Level:
    """The edges out of one level (in order of source, action and pose) and the states they lead to."""

    source: np.ndarray  # per edge, its source's number
    q: np.ndarray
    t: np.ndarray
    number: np.ndarray  # per edge, its end's number among the new states (in order of discovery)
    states: dict[str, np.ndarray]  # STATE_COLUMNS of the new states


class _Steps:
    """The steps of each action from each exit box, one per pose of the action, in one growing store."""

    def __init__(self, builder: _Builder) -> None:
        self.builder = builder
        self.tables: dict[tuple[int, int], tuple[int, int]] = {}  # (exit box, action) -> (first row, rows)
        self.q = np.zeros(0, dtype=np.intp)
        self.t = np.zeros(0)
        self.exit = np.zeros(0, dtype=np.int64)
        self.size = 0

    def rows(self, boxes: np.ndarray, actions: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Per (exit box, action) pair: where its steps start in the store and how many there are."""
        count = len(self.builder.names.keys)
        pairs, which = np.unique(boxes * count + actions, return_inverse=True)
        found = [self._table(int(pair // count), int(pair % count)) for pair in pairs]
        first = np.array([row for row, _ in found], dtype=np.intp)
        length = np.array([n for _, n in found], dtype=np.intp)
        return first[which], length[which]

    def _table(self, box: int, action: int) -> tuple[int, int]:
        found = self.tables.get((box, action))
        if found is None:
            builder = self.builder
            builder.deadline.check()
            key, where = builder.names.keys[action], builder.boxes[box]
            poses = builder.poses[key]
            steps = [(*builder.step(where, key[0], entry, out), builder.number(out)) for entry, out in poses]
            found = self.tables[box, action] = (self.size, len(steps))
            self._store(steps)
        return found

    def _store(self, steps: list[tuple[int, float, int]]) -> None:
        if self.size + len(steps) > len(self.q):
            capacity = max(2 * len(self.q), self.size + len(steps), 1024)
            self.q, self.t, self.exit = (np.resize(a, capacity) for a in (self.q, self.t, self.exit))
        for store, values in zip((self.q, self.t, self.exit), zip(*steps, strict=True), strict=False):
            store[self.size : self.size + len(steps)] = values
        self.size += len(steps)


class _Builder:
    """:meth:`SkeletonGraph.build`'s search, one level of states at a time in integer arrays (:class:`Alphabet`).

    A level is a dict of :data:`STATE_COLUMNS`.
    """

    def __init__(self, problem: Problem, poses: dict, step: Step, deadline: Deadline, max_edges: int) -> None:
        self.problem, self.max_edges, self.edges = problem, max_edges, 0
        self.names = names = Alphabet.of(problem)
        self.poses, self.step, self.deadline = poses, step, deadline
        self.covers = [sum(1 << names.pieces.index(c) for c in problem.covers.get(o, ())) for o in names.objects]
        self.boxes: list[IndexBox | None] = [None]
        self.numbers: dict[IndexBox | None, int] = {None: 0}
        self.steps = _Steps(self)

    def radices(self) -> dict[str, int]:
        """Per state column, one more than its largest value (``held`` and ``last`` counted from -1)."""
        n, m = len(self.names.objects), len(self.names.pieces)
        return {"delivered_set": 1 << n, "held": n + 1, "pushed_set": 1 << m, "last": len(self.names.keys) + 1,
                "exit": len(self.boxes)}  # fmt: skip

    def codes(self, level: dict[str, np.ndarray], columns: Sequence[str]) -> np.ndarray:
        """Per state of ``level``, an integer that tells the states apart as ``columns`` do."""
        radices = self.radices()
        offset = {"held": 1, "last": 1}
        return _codes([(level[c] + offset.get(c, 0), radices[c]) for c in columns])

    def graph(self) -> SkeletonGraph:
        names, problem = self.names, self.problem
        holding = -1 if problem.holding is None else names.objects.index(problem.holding)
        start = {c: np.zeros(1, dtype=names.dtype if c.endswith("_set") else np.int64) for c in STATE_COLUMNS}
        start["held"] += holding
        start["last"] -= 1
        levels, slots, groups = [start], [np.full(1, -1)], [np.zeros(1, dtype=np.intp)]
        group_rows = [start]  # per level, a state of each of its groups
        slot_ids: dict[tuple[int, int], int] = {}
        level_starts, edge_starts = [0, 1], [0]
        src, dst, qs, ts = [], [], [], []
        while level_starts[-1] > level_starts[-2]:
            self.deadline.check()
            edges = self._next(levels[-1], level_starts[-2])
            level = edges.states
            src.append(edges.source)
            dst.append(edges.number + level_starts[-1])
            qs.append(edges.q)
            ts.append(edges.t)
            edge_starts.append(edge_starts[-1] + len(edges.source))
            level_starts.append(level_starts[-1] + len(level["last"]))
            levels.append(level)
            slot_firsts, slot_number = _first_seen(self.codes(level, ("last", "exit")))
            new_slots = zip(level["last"][slot_firsts].tolist(), level["exit"][slot_firsts].tolist(), strict=True)
            slot_of = [slot_ids.setdefault(slot, len(slot_ids)) for slot in new_slots]
            slots.append(np.asarray(slot_of, dtype=np.intp)[slot_number])
            group_firsts, group_number = _first_seen(self.codes(level, STATE_COLUMNS[:4]))
            groups.append(group_number + sum(len(rows["last"]) for rows in group_rows))
            group_rows.append({c: values[group_firsts] for c, values in level.items()})
        column = {c: np.concatenate([level[c] for level in levels]) for c in STATE_COLUMNS}
        full_objects, full_pieces = (1 << len(names.objects)) - 1, (1 << len(names.pieces)) - 1
        return SkeletonGraph(
            level_starts,
            edge_starts,
            np.concatenate(src),
            np.concatenate(dst),
            names,
            *(column[c] for c in STATE_COLUMNS),
            self.boxes,
            np.concatenate(qs),
            np.concatenate(ts),
            ((column["delivered_set"] == full_objects) & (column["pushed_set"] == full_pieces)).astype(bool),
            _bit_counts(column["delivered_set"]),
            (column["last"] >= 0) & (column["last"] < len(names.objects)),  # a place
            np.concatenate(slots),
            [(names.keys[a], self.boxes[x]) for a, x in slot_ids],
            np.concatenate(groups),
            {c: np.concatenate([rows[c] for rows in group_rows]) for c in STATE_COLUMNS[:4]},
        )

    def _next(self, level: dict[str, np.ndarray], first: int) -> _Level:
        """Every edge out of ``level`` (its states numbered from ``first``) and the new states, in order of discovery.

        A move is a state and an action possible from it (in order of state, then action);
        its edges are the action's poses from the state's exit box, listed a chunk of
        about :data:`CHUNK_EDGES` at a time with the deadline checked between chunks. An
        edge's end is its move's (delivered, held, pushed, action), numbered densely, and its
        pose's exit box.
        """
        state, action = np.nonzero(self._possible(level).T)
        after = self._after(level, state, action)
        _, kind = np.unique(self.codes(after, STATE_COLUMNS[:4]), return_inverse=True)
        row, count = self.steps.rows(level["exit"][state], action)
        total = int(count.sum())
        self.edges += total
        if self.edges > self.max_edges:
            raise GraphTooLarge(f"the skeleton graph passes its budget of {self.max_edges:,} edges")
        source, q, exit_box = (np.empty(total, dtype=np.intp) for _ in range(3))
        t, code = np.empty(total), np.empty(total, dtype=np.int64)
        ends = np.cumsum(count)
        lo = 0
        while lo < len(count):  # moves lo .. hi - 1: edges ends[lo - 1] .. ends[hi - 1] - 1
            self.deadline.check()
            start = int(ends[lo - 1]) if lo else 0
            hi = max(lo + 1, int(np.searchsorted(ends, start + CHUNK_EDGES, side="right")))
            moves = slice(lo, hi)
            edges = slice(start, int(ends[hi - 1]))
            within = np.arange(edges.stop - edges.start) - np.repeat(ends[moves] - count[moves] - start, count[moves])
            entry = np.repeat(row[moves], count[moves]) + within
            source[edges] = np.repeat(state[moves], count[moves]) + first
            q[edges], t[edges], exit_box[edges] = self.steps.q[entry], self.steps.t[entry], self.steps.exit[entry]
            code[edges] = np.repeat(kind[moves], count[moves]) * len(self.boxes) + exit_box[edges]
            lo = hi
        firsts, number = _first_seen(code)
        move = np.searchsorted(ends, firsts, side="right")  # the move of each new state's first edge
        states = {c: values[move] for c, values in after.items()} | {"exit": exit_box[firsts]}
        return _Level(source, q, t, number, states)

    def _after(self, level: dict[str, np.ndarray], state: np.ndarray, action: np.ndarray) -> dict[str, np.ndarray]:
        """The (delivered, held, pushed, last action) after each move: ``action`` done from ``state``."""
        n, dtype = len(self.names.objects), self.names.dtype
        keys = len(self.names.keys)
        places = np.array([1 << a if a < n else 0 for a in range(keys)], dtype=dtype)
        pushes = np.array([1 << (a - 2 * n) if a >= 2 * n else 0 for a in range(keys)], dtype=dtype)
        held = np.where(action < n, -1, np.where(action < 2 * n, action - n, level["held"][state]))
        return {
            "delivered_set": level["delivered_set"][state] | places[action],
            "held": held.astype(np.int64),
            "pushed_set": level["pushed_set"][state] | pushes[action],
            "last": action.astype(np.int64),
        }

    def _possible(self, level: dict[str, np.ndarray]) -> np.ndarray:
        """``[action, state]``: whether the action can be done next from the state (:func:`skeleton_moves`' rule)."""
        names, n = self.names, len(self.names.objects)
        delivered, held, pushed = level["delivered_set"], level["held"], level["pushed_set"]
        possible = np.zeros((len(names.keys), len(held)), dtype=bool)
        for i in range(n):
            cover = self.covers[i]
            possible[i] = (held == i) & (pushed & cover == cover)  # a place
            possible[n + i] = (held == -1) & (delivered >> i & 1 == 0)  # a pick
        for c in range(len(names.pieces)):
            possible[2 * n + c] = pushed >> c & 1 == 0
        return possible

    def number(self, box: IndexBox) -> int:
        """The number of an exit box (a new one: the next)."""
        if box not in self.numbers:
            self.numbers[box] = len(self.boxes)
            self.boxes.append(box)
        return self.numbers[box]
