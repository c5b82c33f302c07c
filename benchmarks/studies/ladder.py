"""The ladder study's tools: success against the number of objects k, measured by the benchmark runner.

The curve itself is ``fetchcarry benchmark --split objects-v2:dev`` (recipes are chosen
there) and ``--split objects-v2:test`` (the reported figures): each split draws
``objects-1`` .. ``objects-12`` in turn, and ``summary.md`` gives success and the cost
ratio per k (``objects.png`` draws them). This module adds what the study needs beside it
(``benchmarks/studies/ladder.sh`` runs the whole study):

- ``goals RESULTS.json``: the ladder's goals (:data:`GOALS`) met or missed, per policy;
- ``variant RUN OUT NAME=true ...``: a copy of a run folder acting with other episode
  rules (:data:`ACTING_OPTIONS`), to compare rules on the same network;
- ``trace RUN --k K --seeds ...``: what a run chose at every phase of some episodes.

Run it from the repository's root: ``python -m benchmarks.studies.ladder goals|variant|trace``.
"""

from __future__ import annotations

import argparse
import json
import shutil
from collections.abc import Sequence
from pathlib import Path
from typing import Any

import numpy as np

from fetchcarry_env.observation import FIELDS, observation_layout
from fetchcarry_env.phases import PhaseLayout
from training.envs import make_env
from training.evaluation.results import read_results
from training.learners.runs import load_checkpoint, write_metrics
from training.resolve import build, resolve
from training.rollout import run_episode
from training.stats import wilson

GOALS = {6: 0.80, 8: 0.60}
"""The ladder's goals: success at least this on ``objects-k`` (a set encoder trained on 1-4 objects)."""
MAX_K = 12  # the objects-k families the objects splits draw


def family(k: int) -> str:
    """The family of ``k`` objects."""
    return f"objects-{k}"


def goals(records: list[dict[str, Any]]) -> list[str]:
    """One line per policy and goal of :data:`GOALS`: its success on ``objects-k`` with a 95 % Wilson interval, met
    or missed (a policy without episodes on that k is left out)."""
    lines = []
    for policy in sorted({r["policy"] for r in records}):
        for k, goal in GOALS.items():
            outcomes = [bool(r["success"]) for r in records if r["policy"] == policy and r["source"] == family(k)]
            if not outcomes:
                continue
            rate, (low, high) = float(np.mean(outcomes)), wilson(sum(outcomes), len(outcomes))
            verdict = "met" if rate >= goal else "missed"
            lines.append(
                f"{policy}: at least {goal:.0%} on {family(k)}: {verdict} ({rate:.0%} [{low:.0%}, {high:.0%}], "
                f"{len(outcomes)} episodes)"
            )
    return lines


def trace(name: str, k: int, seed: int) -> str:
    """One episode of the run folder ``name`` on ``objects-k``, one word per phase: what it chose, in what state.

    Each word is the candidate's kind (four letters) and slot, ``(hN)`` while object N is in
    the hand, and ``[dD|A]``: D objects delivered and A candidates allowed in the state it
    chose in. For example ``pick1[d1|36] plac1(h1)[d0|41]`` is a delivered object picked up
    and placed back. The line starts with the seed, the success and the phases.
    """
    import torch

    torch.set_num_threads(1)
    spec = resolve(name)
    env = make_env(spec.interface, family=family(k))
    try:
        policy, capacity = build(spec, env), env.unwrapped.capacity
        layout, objects, fields = (
            PhaseLayout.for_postures(capacity=capacity),
            observation_layout(capacity)["objects"],
            FIELDS["object"],
        )
        words: list[str] = []

        def observe(observation: dict[str, np.ndarray], action: Any, mask: np.ndarray) -> None:
            rows = np.asarray(observation["observation"])[objects].reshape(capacity.objects, len(fields))
            present = rows[:, fields.index("present")] > 0.5
            held = np.flatnonzero(present & (rows[:, fields.index("held")] > 0.5))
            delivered = int(rows[present, fields.index("delivered")].sum())
            candidate = layout.describe(int(action))
            hand = f"(h{held[0]})" if len(held) else ""
            words.append(f"{candidate.kind[:4]}{candidate.slot}{hand}[d{delivered}|{int(mask.sum())}]")

        episode = run_episode(env, policy, seed, deterministic=True, stop_on_failure=False, observe=observe)
    finally:
        env.close()
    return f"{seed} {'success' if episode.info['is_success'] else 'failure'} {episode.figures.steps} " + " ".join(words)


ACTING_OPTIONS = ("avoid_repeats", "avoid_returns", "push_after_approach", "skip_delivered")
"""The BC policy's acting options (:class:`training.learners.options.BCConfig`): they change no weight."""


def variant(run: Path, out: Path, settings: dict[str, bool]) -> Path:
    """A copy of the run folder ``run`` at ``out`` (a new folder) acting with ``settings`` (acting options only).

    The weights and metrics are copied as they are; ``config.json``'s ``config`` gains the
    settings, so the same network acts with other episode rules (``avoid_returns``,
    ``skip_delivered``, ...). A DAgger run stopped before its last iteration (no weights yet)
    gives the network of its last finished iteration (its ``checkpoint.pt``): the copy is
    complete, its ``data`` saying so. ``ValueError`` for another option or an existing ``out``.
    """
    import torch

    unknown = sorted(set(settings) - set(ACTING_OPTIONS))
    if unknown:
        raise ValueError(f"not acting options: {', '.join(unknown)} (choose from {', '.join(ACTING_OPTIONS)})")
    if out.exists():
        raise ValueError(f"{out} exists already")
    config = json.loads((run / "config.json").read_text())
    config["config"].update(settings)
    checkpoint = None
    if not config.get("complete"):
        checkpoint = load_checkpoint(run)
        if config["kind"] != "dagger" or checkpoint is None or not checkpoint.get("metrics"):
            raise ValueError(f"{run} is not finished, and is not a DAgger run with a finished iteration")
        rows = checkpoint["metrics"]
        config["data"] = {"expert_labels": int(rows[-1]["expert_labels"]), "episodes": int(checkpoint["episodes"]),
                          "stopped_after_iteration": int(rows[-1]["iteration"])}  # fmt: skip
        config["complete"] = True
    out.mkdir(parents=True)
    if checkpoint is not None:
        torch.save(checkpoint["network"], out / "model.pt")
        write_metrics(out, [dict(row) for row in checkpoint["metrics"]])
    for name in ("model.pt", "metrics.csv") if checkpoint is None else ():
        if (run / name).exists():
            shutil.copyfile(run / name, out / name)
    (out / "config.json").write_text(json.dumps(config, indent=2) + "\n")
    return out


def _settings(pairs: Sequence[str]) -> dict[str, bool]:
    """``["skip_delivered=true", ...]`` -> ``{"skip_delivered": True, ...}`` (``ValueError`` on other text)."""
    settings = {}
    for pair in pairs:
        name, _, value = pair.partition("=")
        if value.lower() not in ("true", "false"):
            raise ValueError(f"expected NAME=true or NAME=false, got {pair!r}")
        settings[name] = value.lower() == "true"
    return settings


def main(argv: Sequence[str] | None = None) -> None:
    """``goals``, ``variant`` or ``trace`` (see the module's docstring)."""
    parser = argparse.ArgumentParser(prog="python -m benchmarks.studies.ladder", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    judging = commands.add_parser("goals", help="the ladder's goals, met or missed, from a benchmark's results")
    judging.add_argument("results", type=Path, help="results.json of fetchcarry benchmark on an objects split")
    varying = commands.add_parser("variant", help="copy a run folder, acting with other episode rules")
    varying.add_argument("run", type=Path, help="a finished bc or dagger run folder")
    varying.add_argument("out", type=Path, help="the new run folder")
    varying.add_argument("settings", nargs="+", metavar="NAME=true|false", help=", ".join(ACTING_OPTIONS))
    tracing = commands.add_parser("trace", help="print one word per phase of a run's episodes (what it chose)")
    tracing.add_argument("run", help="a run folder")
    tracing.add_argument("--k", type=int, required=True, help="objects (the family objects-K)")
    tracing.add_argument("--seeds", type=int, nargs="+", required=True, help="episode seeds")
    args = parser.parse_args(argv)
    try:
        if args.command == "goals":
            print("\n".join(goals(read_results(args.results))))
        elif args.command == "variant":
            print(variant(args.run, args.out, _settings(args.settings)))
        else:
            if not 1 <= args.k <= MAX_K:
                raise ValueError(f"--k must be 1 to {MAX_K}, got {args.k}")
            for seed in args.seeds:
                print(trace(args.run, args.k, seed), flush=True)
    except (ValueError, OSError) as error:  # bad input: a BenchmarkError is a ValueError too
        parser.exit(2, f"error: {error}\n")


if __name__ == "__main__":
    main()
