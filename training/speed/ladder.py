"""The ladder: success and cost ratio against the number of objects k, on ``objects-1`` .. ``objects-8``.

``python -m training.speed.ladder run --policies RUN_DIR greedy random-phases --out DIR``
runs each policy for one episode per seed of every ``objects-k`` family (at the family's
observation capacity: a set-encoder run trained on four objects acts on eight) and
appends one record per episode to ``DIR/results.json`` (rewritten after each episode,
so an interrupted run resumes where it stopped); ``--expert-ks`` runs the MILP expert
too on those k, for the cost ratio to the expert. ``python -m training.speed.ladder
report DIR`` writes ``DIR/summary.md`` (success with its 95 % Wilson interval, cost
ratio to greedy and to the expert, the share of objects delivered, per policy and k; the
issue's goals met or missed) and ``DIR/ladder.png``. ``variant RUN OUT NAME=true ...`` copies
a run folder acting with other episode rules (:data:`ACTING_OPTIONS`); ``trace RUN --k K
--seeds ...`` prints what a run chose at every phase of some episodes.

Seeds (``--seeds``): ``dev`` counts up from :data:`DEV_FIRST_SEED` (the held-out seeds no
dataset is made from; recipes are chosen there, on ``objects-5`` and ``objects-6``),
``test`` from :data:`TEST_FIRST_SEED`, a block of the evaluation seeds (from 10^9) that
no split uses and no recipe looked at. Travel costs are the paper's (metres).
"""

from __future__ import annotations

import argparse
import json
import math
import shutil
from collections.abc import Iterable, Sequence
from dataclasses import asdict
from pathlib import Path
from typing import Any

import numpy as np
from tqdm import tqdm

from expert import ExpertPolicy
from fetchcarry_env.jsontext import read_json
from fetchcarry_env.observation import FIELDS, observation_layout
from fetchcarry_env.phases import PhaseLayout
from training.data.expert_labels import expert_episode
from training.envs import make_env
from training.errors import BenchmarkError
from training.evaluation.splits import EVAL_SEED_BASE, SPLIT_BLOCK
from training.learners.heldout import EpisodeResult, Summary, summarise
from training.learners.runs import load_checkpoint, write_metrics
from training.resolve import build, resolve
from training.rollout import run_episode

DEV_FIRST_SEED = 100_000  # the held-out seeds (training/learners/heldout.py): recipes are chosen here
TEST_FIRST_SEED = EVAL_SEED_BASE + 90 * SPLIT_BLOCK  # an evaluation block no split uses: the reported figures
KS = tuple(range(1, 9))  # the objects-k families of the curve
GOALS = {6: 0.80, 8: 0.60}  # the goals: success at least this on objects-k
RESULTS = "results.json"
EXPERT = "expert"
MAX_RESULTS_BYTES = 64 * 2**20  # a results.json larger than this is refused


def family(k: int) -> str:
    """The family of ``k`` objects."""
    return f"objects-{k}"


def seeds_of(which: str, episodes: int) -> list[int]:
    """The first ``episodes`` seeds of ``dev`` or ``test``."""
    first = {"dev": DEV_FIRST_SEED, "test": TEST_FIRST_SEED}[which]
    return list(range(first, first + episodes))


def read_records(out: Path) -> list[dict[str, Any]]:
    """The records of ``out/results.json`` (none if it does not exist yet)."""
    path = out / RESULTS
    return list(read_json(path, MAX_RESULTS_BYTES)["records"]) if path.exists() else []


def write_records(out: Path, records: list[dict[str, Any]]) -> None:
    """Rewrite ``out/results.json`` with ``records`` (through a temporary file, so it is never half written)."""
    out.mkdir(parents=True, exist_ok=True)
    temporary = out / (RESULTS + ".tmp")
    temporary.write_text(json.dumps({"format": "fetchcarry-ladder/1", "records": records}, indent=1) + "\n")
    temporary.replace(out / RESULTS)


def policy_episodes(name: str, k: int, seeds: Iterable[int]) -> Iterable[tuple[EpisodeResult, dict[str, Any]]]:
    """Episodes of the policy ``name`` (a run folder, ``greedy``, ``random-phases``, or ``expert``) on ``objects-k``.

    Each comes with the objects it delivered and its outcome (``delivered``, ``truncated``
    at the env's 50 phases, ...), where the episode's figures say them.

    A learned or random policy acts in the candidate phases at the family's capacity;
    ``greedy`` in the env's own actions; the ``expert`` through the candidate phases as
    its demonstrations were recorded (within its node budget, its 10 s limit a safety stop).
    """
    spec = resolve(name) if name != EXPERT else None
    interface = spec.interface if spec is not None else "phases"
    env = make_env(interface, family=family(k))  # the family's capacity, not the run's
    try:
        if spec is None:
            expert = ExpertPolicy(env, interface="env")  # its own env actions, as expert_episode executes them
            for seed in seeds:
                record = expert_episode(env, expert, seed)
                result = EpisodeResult(seed, bool(record.success), float(record.travel_cost), int(record.steps), 0)
                yield result, {}
            return
        policy = build(spec, env)
        deterministic = name != "random-phases"  # the masked random policy is seeded by the episode's seed
        for seed in seeds:
            episode = run_episode(env, policy, seed, deterministic=deterministic, stop_on_failure=False)
            figures, info = episode.figures, episode.info
            result = EpisodeResult(seed, bool(info["is_success"]), float(info["travel_cost"]), figures.steps,
                                   figures.invalid_actions, figures.policy_s)  # fmt: skip
            yield result, {"delivered": figures.delivered, "outcome": figures.outcome}
    finally:
        env.close()


def label(name: str) -> str:
    """How a policy is named in the records: a run folder by its folder name."""
    return Path(name).name if Path(name).is_dir() else name


def run(policies: Sequence[str], ks: Sequence[int], seeds: Sequence[int], out: Path, progress: bool = True) -> None:
    """Append to ``out/results.json`` every (policy, k, seed) episode it does not hold yet."""
    import torch  # a learned policy's forward pass: one thread (two were 27x slower on a loaded 2-core machine)

    torch.set_num_threads(1)
    records = read_records(out)
    done = {(r["policy"], r["k"], r["seed"]) for r in records}
    todo = [(p, k) for p in policies for k in ks if any((label(p), k, s) not in done for s in seeds)]
    bar = tqdm(total=sum(1 for p, k in todo for s in seeds if (label(p), k, s) not in done), disable=not progress)
    for name, k in todo:
        missing = [s for s in seeds if (label(name), k, s) not in done]
        bar.set_description(f"{label(name)} on {family(k)}")
        for result, extra in policy_episodes(name, k, missing):
            records.append({"policy": label(name), "family": family(k), "k": k, **asdict(result), **extra})
            write_records(out, records)
            bar.update()
    bar.close()


def summaries(records: list[dict[str, Any]]) -> dict[tuple[str, int], dict[str, Any]]:
    """Per (policy, k): the summary, with the cost ratio to greedy and to the expert (where they ran)."""
    by: dict[tuple[str, int], list[EpisodeResult]] = {}
    for r in records:
        fields = {key: r[key] for key in ("seed", "success", "travel_cost", "phases", "refused", "decision_s")}
        by.setdefault((r["policy"], r["k"]), []).append(EpisodeResult(**fields))
    delivered: dict[tuple[str, int], list[float]] = {}
    for r in records:
        if "delivered" in r:
            delivered.setdefault((r["policy"], r["k"]), []).append(r["delivered"] / r["k"])
    costs = {key: {e.seed: e.travel_cost for e in results if e.success} for key, results in by.items()}
    table = {}
    for (policy, k), results in by.items():
        to_greedy: Summary = summarise(results, costs.get(("greedy", k), {}))
        to_expert: Summary = summarise(results, costs.get((EXPERT, k), {}))
        shares = delivered.get((policy, k))
        table[policy, k] = {**asdict(to_greedy), "cost_to_greedy": to_greedy.cost_ratio,
                            "cost_to_expert": to_expert.cost_ratio,
                            "delivered": float(np.mean(shares)) if shares else math.nan}  # fmt: skip
    return table


def _cell(value: float, form: str) -> str:
    return "-" if value is None or math.isnan(value) else format(value, form)


def markdown(table: dict[tuple[str, int], dict[str, Any]]) -> str:
    """The table (one row per policy and k) and the goals, met or missed, of each learned policy."""
    lines = ["| policy | k | episodes | success [95 % Wilson] | delivered | cost / greedy | cost / expert | phases"
             " | refused |", "|---|---|---|---|---|---|---|---|---|"]  # fmt: skip
    for (policy, k), s in sorted(table.items()):
        lines.append(
            f"| {policy} | {k} | {s['episodes']} | {s['success']:.0%} [{s['success_low']:.0%}, {s['success_high']:.0%}]"
            f" | {_cell(s['delivered'], '.0%')} | {_cell(s['cost_to_greedy'], '.2f')}"
            f" | {_cell(s['cost_to_expert'], '.2f')}"
            f" | {s['phases']:.1f} | {s['refused']:.1f} |"
        )
    lines.append("")
    for policy in sorted({p for p, _ in table} - {"greedy", "random-phases", EXPERT}):
        for k, goal in GOALS.items():
            s = table.get((policy, k))
            if s is not None:
                verdict = "met" if s["success"] >= goal else "missed"
                lines.append(f"- {policy}: at least {goal:.0%} on objects-{k}: {verdict} ({s['success']:.0%})")
    return "\n".join(lines) + "\n"


def plot(table: dict[tuple[str, int], dict[str, Any]], path: Path) -> None:
    """Success (95 % Wilson interval) and cost ratio to greedy against k, one line per policy; the goals marked."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    figure, (left, right) = plt.subplots(1, 2, figsize=(11, 4.2))
    policies = sorted({p for p, _ in table})
    for index, policy in enumerate(policies):
        ks = sorted(k for p, k in table if p == policy)
        rows = [table[policy, k] for k in ks]
        shifted = np.array(ks) + 0.06 * (index - (len(policies) - 1) / 2)  # intervals apart
        success = np.array([r["success"] for r in rows])
        error = np.array([success - [r["success_low"] for r in rows], [r["success_high"] for r in rows] - success])
        colour = f"C{index}"
        left.errorbar(shifted, success, yerr=error, marker="o", capsize=3, label=policy, color=colour)
        if policy != "greedy":
            right.plot(ks, [r["cost_to_greedy"] for r in rows], marker="o", label=policy, color=colour)
    for k, goal in GOALS.items():
        left.plot([k], [goal], marker="*", markersize=14, color="black", linestyle="none")
    left.plot([], [], marker="*", color="black", linestyle="none", label="goal (k=6: 80 %, k=8: 60 %)")
    left.axvspan(0.5, 4.5, color="0.92", zorder=0, label="trained on (k = 1..4)")
    left.set(xlabel="objects k", ylabel="success (95 % Wilson interval)", ylim=(-0.03, 1.03), xticks=KS)
    right.axhline(1.0, color="0.6", linewidth=1)
    right.set(xlabel="objects k", ylabel="travel cost / greedy's (solved by both)", xticks=KS)
    left.legend(fontsize=8, loc="lower left")
    right.legend(fontsize=8)
    figure.suptitle("objects-k: trained on k = 1..4, tested on k = 1..8 (test seeds)")
    figure.tight_layout()
    figure.savefig(path, dpi=110)
    plt.close(figure)


def report(out: Path, also: Sequence[Path] = ()) -> str:
    """Write ``out/summary.md`` and ``out/ladder.png`` from ``out/results.json``; return the markdown.

    The records of the folders ``also`` (run apart, for example by another process) are
    merged into ``out/results.json`` first; a (policy, k, seed) ``out`` holds already is kept.
    """
    records = read_records(out)
    done = {(r["policy"], r["k"], r["seed"]) for r in records}
    for folder in also:
        records += [r for r in read_records(folder) if (r["policy"], r["k"], r["seed"]) not in done]
        done = {(r["policy"], r["k"], r["seed"]) for r in records}
    write_records(out, records)
    table = summaries(records)
    text = markdown(table)
    (out / "summary.md").write_text(text)
    plot(table, out / "ladder.png")
    return text


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


def _ks(text: str) -> list[int]:
    """``1-8`` or ``5,6`` -> the list of k."""
    if "-" in text:
        low, high = (int(part) for part in text.split("-", 1))
        return list(range(low, high + 1))
    return [int(part) for part in text.split(",") if part]


def main(argv: Sequence[str] | None = None) -> None:
    """``run`` episodes into a results folder, or ``report`` one."""
    parser = argparse.ArgumentParser(prog="python -m training.speed.ladder", description=__doc__.split("\n\n")[0])
    commands = parser.add_subparsers(dest="command", required=True)
    running = commands.add_parser("run", help="run policies on objects-k, appending to OUT/results.json")
    running.add_argument("--policies", nargs="+", required=True, help="run folders, greedy, random-phases")
    running.add_argument("--ks", default="1-8", help="the k to run, e.g. 1-8 or 5,6 (default 1-8)")
    running.add_argument("--expert-ks", default="", help="the k the MILP expert runs on too (default none)")
    running.add_argument("--seeds", choices=("dev", "test"), default="test", help="seed block (default test)")
    running.add_argument("--episodes", type=int, default=50, help="seeds per k (default 50)")
    running.add_argument("--out", type=Path, required=True, help="results folder")
    running.add_argument("--no-progress", action="store_true", help="no progress bar")
    reporting = commands.add_parser("report", help="write OUT/summary.md and OUT/ladder.png")
    reporting.add_argument("out", type=Path, help="results folder")
    reporting.add_argument("--also", type=Path, nargs="*", default=[], help="folders whose records to merge into OUT")
    varying = commands.add_parser("variant", help="copy a run folder, acting with other episode rules")
    varying.add_argument("run", type=Path, help="a finished bc or dagger run folder")
    varying.add_argument("out", type=Path, help="the new run folder")
    varying.add_argument("settings", nargs="+", metavar="NAME=true|false", help=", ".join(ACTING_OPTIONS))
    tracing = commands.add_parser("trace", help="print one word per phase of a run's episodes (what it chose)")
    tracing.add_argument("run", help="a run folder")
    tracing.add_argument("--k", type=int, required=True, help="objects (the family objects-K)")
    tracing.add_argument("--seeds", type=int, nargs="+", required=True, help="episode seeds")
    args = parser.parse_args(argv)
    if args.command == "trace":
        if not 1 <= args.k <= max(KS):
            parser.exit(2, f"error: --k must be 1 to {max(KS)}, got {args.k}\n")
        try:
            for seed in args.seeds:
                print(trace(args.run, args.k, seed), flush=True)
        except BenchmarkError as error:
            parser.exit(2, f"error: {error}\n")
        return
    if args.command == "variant":
        try:
            print(variant(args.run, args.out, _settings(args.settings)))
        except (ValueError, OSError) as error:
            parser.exit(2, f"error: {error}\n")
        return
    if args.command == "run":
        seeds = seeds_of(args.seeds, args.episodes)
        run(args.policies, _ks(args.ks), seeds, args.out, progress=not args.no_progress)
        if args.expert_ks:
            run([EXPERT], _ks(args.expert_ks), seeds, args.out, progress=not args.no_progress)
    print(report(args.out, args.also if args.command == "report" else ()), end="")


if __name__ == "__main__":
    main()
