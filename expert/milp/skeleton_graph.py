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
    """

    q: np.ndarray
    nodes: list[tuple]  # (delivered, held, pushed, last action)
    finished: np.ndarray


@dataclass(frozen=True)
class SkeletonGraph(Layers):
    """The states (the nodes, in order of discovery) and the edges between them.

    ``src[e] -> dst[e]`` costs at least ``q[e]`` phases and ``t[e]`` metres of travel.
    Per state: ``finished`` (every object delivered, every covering piece pushed),
    ``delivered`` (how many objects), ``placed`` (its last action is a place),
    ``slot`` (the number of its last action and exit box in ``slots``; the start's is -1)
    and ``group`` (its node in :attr:`actions`, the graph without poses).
    """

    states: list[tuple]  # (delivered, held, pushed, last action, its exit box)
    q: np.ndarray
    t: np.ndarray
    finished: np.ndarray
    delivered: np.ndarray
    placed: np.ndarray
    slot: np.ndarray
    slots: list[tuple[Key, IndexBox]]
    group: np.ndarray
    groups: list[tuple]  # (delivered, held, pushed, last action), numbered level by level

    @classmethod
    def build(
        cls, problem: Problem, poses: dict[Key, tuple[tuple[IndexBox, IndexBox], ...]], step: Step,
        deadline: Deadline = NEVER,
    ) -> SkeletonGraph:  # fmt: skip
        """Every state reachable from the start; ``poses[action]`` lists its (entry, exit) boxes.

        A state is found by its exit box's number (hashed in C; a box's hash runs Python),
        and the steps of an action from a box, which depend on nothing else, are listed once.
        """
        start = (frozenset(), problem.holding, frozenset(), None, None)
        states = [start]
        boxes: list[IndexBox | None] = [None]
        numbers: dict[IndexBox | None, int] = {None: 0}
        exits = [0]  # per state, its exit box's number
        ids = {(start[0], start[1], start[2], None, 0): 0}
        steps: dict = {}  # (exit number, action) -> [(phases, travel, next exit number)]
        slot_ids: dict[tuple[Key, int], int] = {}
        slot_of = [-1]
        group_ids: dict[tuple, int] = {start[:4]: 0}
        group_of = [0]

        def number(box: IndexBox) -> int:
            if box not in numbers:
                numbers[box] = len(boxes)
                boxes.append(box)
            return numbers[box]

        level_starts, edge_starts = [0, 1], [0]
        src: list[int] = []
        dst: list[int] = []
        qs: list[int] = []
        ts: list[float] = []
        while level_starts[-1] > level_starts[-2]:
            for sid in range(level_starts[-2], level_starts[-1]):
                deadline.check()
                delivered, held, pushed, _, where = states[sid]
                for key, (d, h, p) in skeleton_moves(problem, delivered, held, pushed):
                    found = steps.get((exits[sid], key))
                    if found is None:
                        found = steps[exits[sid], key] = [
                            (*step(where, key[0], entry, exit_box), number(exit_box)) for entry, exit_box in poses[key]
                        ]
                    for q, t, x in found:
                        j = ids.get((d, h, p, key, x))
                        if j is None:
                            j = ids[d, h, p, key, x] = len(states)
                            states.append((d, h, p, key, boxes[x]))
                            exits.append(x)
                            slot_of.append(slot_ids.setdefault((key, x), len(slot_ids)))
                            group_of.append(group_ids.setdefault((d, h, p, key), len(group_ids)))
                        src.append(sid)
                        dst.append(j)
                        qs.append(q)
                        ts.append(t)
            edge_starts.append(len(src))
            level_starts.append(len(states))
        return cls(
            level_starts,
            edge_starts,
            np.asarray(src, dtype=np.intp),
            np.asarray(dst, dtype=np.intp),
            states,
            np.asarray(qs, dtype=np.intp),
            np.asarray(ts, dtype=float),
            np.array([all_done(problem, s[0], s[2]) for s in states], dtype=bool),
            np.array([len(s[0]) for s in states], dtype=np.intp),
            np.array([s[3] is not None and s[3][0] == "place" for s in states], dtype=bool),
            np.asarray(slot_of, dtype=np.intp),
            [(key, boxes[x]) for key, x in slot_ids],
            np.asarray(group_of, dtype=np.intp),
            list(group_ids),
        )

    def within(self, n_phases: int) -> SkeletonGraph:
        """The graph without the edges of more than ``n_phases - 1`` phases (no plan of ``n_phases`` takes one).

        Its states are all kept: one reached only by such edges is reached by no plan, and
        every bound through it is ``inf``.
        """
        return self._keeping(self.q <= n_phases - 1)

    def in_order(self, order: Sequence[str], deliver: Collection[str]) -> SkeletonGraph:
        """The graph without the picks out of ``order``, as :func:`expert.milp.order.add_pick_order` restricts a model.

        Of ``order``'s objects the model delivers (``deliver``), each one after the first is
        picked only once the one before it is delivered; any other object at any time. The
        plans of the restricted model map onto this graph's paths, so its bounds hold for them.
        """
        chain = [target for target in order if target in deliver]
        bit = {target: 1 << i for i, target in enumerate(chain)}  # a set of delivered objects is a sum of bits
        before = {after: bit[first] for first, after in pairwise(chain)}

        def needed(state: tuple) -> int:  # what must be delivered before the action that led to ``state``
            key = state[3]
            return before.get(key[1], 0) if key is not None and key[0] == "pick" else 0

        delivered = np.array([sum(bit.get(o, 0) for o in state[0]) for state in self.states], dtype=np.int64)
        need = np.array([needed(state) for state in self.states], dtype=np.int64)[self.dst]
        return self._keeping((need & delivered[self.src]) == need)

    def _keeping(self, keep: np.ndarray) -> SkeletonGraph:
        """The graph with the edges where ``keep`` is True (its states all kept)."""
        if keep.all():
            return self
        kept_before = np.concatenate(([0], np.cumsum(keep)))
        return dataclasses.replace(
            self,
            edge_starts=[int(kept_before[e]) for e in self.edge_starts],
            src=self.src[keep],
            dst=self.dst[keep],
            q=self.q[keep],
            t=self.t[keep],
        )

    @functools.cached_property
    def actions(self) -> ActionGraph:
        """This graph with the states of one (delivered, held, pushed, last action) merged, each edge its least ``q``.

        A state's groups are numbered in order of discovery, so level by level, and every
        exit box of the last action is among a group's states (each action's poses all
        lead on from any state), so an edge's ``q`` is the least over both actions' poses.
        """
        count = len(self.groups)
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
            level_starts, edge_starts, src, dst, np.minimum.reduceat(self.q[order], firsts), self.groups, finished
        )
