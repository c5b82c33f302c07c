"""``python -m benchmarks env|planner|anytime|push|generate|phases|ppo``: the speed benchmarks' options and tables.

The measurements live in the modules beside this one (``env``, ``planner``, ``anytime``,
``push``, ``generate``, ``phases``, ``ppo``) and return figures; this module parses the
options, runs them and prints the figures for people (or as JSON with ``--json``).
"""

from __future__ import annotations

import argparse
import json
import os
import sys
import time
from dataclasses import asdict
from pathlib import Path
from typing import Any, TextIO

from benchmarks.speed import anytime as anytime_speed
from benchmarks.speed import env as env_speed
from benchmarks.speed import generate as generate_speed
from benchmarks.speed import planner as planner_speed
from benchmarks.speed import ppo as ppo_speed
from benchmarks.speed import push as push_speed
from fetchcarry_env.errors import InputError
from training.cli.arguments import positive_float, positive_int
from training.cli.episodes import families
from training.cli.files import check_readable, check_writable
from training.cli.options import Command
from training.cli.seeds import seed
from training.cli.text import echo
from training.data.sources import EpisodeSource
from training.learners.options import MAX_ENVS, PPOOptions, check_family

ENV_DESCRIPTION = (
    "Run, in this process, the example scenario of the scenario format and the MILP expert's optimal plan for it "
    "(two moves, a push, a move, a pick, a move, a place), episode after episode, and time every reset and step. "
    "Prints, with the project's goal for each: reset of an unchanged layout, move, pick and place steps per second, "
    "a push step as a multiple of the physics steps it simulates, a random masked policy's steps per second "
    "(random scenarios of the default family, resets included) and the peak memory; next to each figure, the cost "
    "of the PyBullet calls that step cannot avoid, measured on the same world."
)
PLANNER_DESCRIPTION = (
    "Plan seeded scenarios of the paper's Section V in this process (one planning call each, model building "
    "included; one untimed warm-up call first pays for the imports) and print, per case, the median, 95th "
    "percentile, mean (SD) and maximum of the planning time, the statuses (every plan must be optimal), the "
    "phases of the plans, the paper's mean (SD) and our goal; then where the time goes: preprocessing, the lower "
    "bound and the reachability check, model building, SCIP proving smaller phase counts infeasible, and SCIP "
    "solving the final one. Every plan is also checked by the validator."
)

# the benchmarks' texts in --help (their options are added by the _register_* functions below)
ENV_COMMAND = Command(
    name="env",
    help="env speed: reset, move/pick/place/push steps, a random masked policy, peak memory",
    description=ENV_DESCRIPTION,
    epilog="Exit status: 0, or 1 with --strict when a goal is missed.",
)
PLANNER_COMMAND = Command(
    name="planner",
    help="the paper's Section V timings: V-B, V-C, L corridor, 2-6 objects, covered goals",
    description=PLANNER_DESCRIPTION,
    epilog="Exit status: 0 every plan optimal and valid, 1 not, 2 bad input. Times are printed in ms.",
)
ANYTIME_COMMAND = Command(
    name="anytime",
    help="the planner under 0.1 s and 1 s limits: first plans, how good they are, their proven gaps",
    description="Plan the scale cases of the planner benchmark (4, 5 and 6 objects, every goal covered with 3; "
    "seed 2024) at time limits of 0.1 s and 1 s and once at 30 s as the reference, check every plan with "
    "the validator, and print per case and limit: valid plans, optimal ones, plans with the reference's "
    "phases, how many lie within 5 % of a proven optimum, how far each one's Eq. 1 lies above the "
    "reference and the gaps the planner proved. Takes several minutes.",
)
PUSH_COMMAND = Command(
    name="push",
    help="push-aside while carrying: phases and travel of the plans on the push family and patterns A-E",
    description="Plan the push family (seeds 0-39) and the paper's Table I patterns A-E (the paper-push "
    "families, seeds 0-7 each) and print per group the plans' mean phases and travel (Eq. 1's distance "
    "term, metres), how many plans push while holding the object and the median planning time; with "
    "--compare, the records of another checkout scenario by scenario: travel and phases before and after.",
)
GENERATE_COMMAND = Command(
    name="generate",
    help="episodes per second per worker, planning vs simulation, speed-up with more workers",
    description="Run the same seeded expert episodes of each family with each worker count (the process "
    "pool of dataset generation, start-up included) and print episodes per second, episodes per second "
    "per worker, the seconds per episode in the planner, in the rest of the policy and in the simulation, "
    "and the speed-up over the first worker count.",
)


def register(bench: argparse._SubParsersAction) -> None:
    """Add the speed benchmarks: env, planner, anytime, push, generate, phases, ppo."""
    _register_env(bench)
    _register_planner(bench)
    _register_anytime(bench)
    _register_push(bench)
    _register_generate(bench)
    _register_phases(bench)
    _register_ppo(bench)


def _add_seed(parser: argparse.ArgumentParser, default: int, meaning: str) -> None:
    """``--seed S``: ``meaning``, and its default."""
    parser.add_argument("--seed", type=seed, default=default, metavar="S", help=f"{meaning} (default {default})")


# ---------------------------------------------------------------------------- bench env
def _register_env(bench: argparse._SubParsersAction) -> None:
    parser = ENV_COMMAND.add(bench, run_env)
    counts = (
        ("--episodes", env_speed.DEFAULT_EPISODES, "episodes of the plan"),
        ("--resets", env_speed.DEFAULT_RESETS, "resets of the same layout"),
        ("--random-steps", env_speed.DEFAULT_RANDOM_STEPS, "steps of the random masked policy"),
        ("--obs-episodes", env_speed.DEFAULT_OBS_EPISODES, "episodes of the plan in each obs_mode"),
    )
    for flag, default, meaning in counts:
        parser.add_argument(
            flag, type=positive_int, default=default, metavar="N", help=f"{meaning} (default {default})"
        )
    _add_seed(parser, env_speed.DEFAULT_SEED, "seed of the resets and the policy")
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    parser.add_argument("--strict", action="store_true", help="exit status 1 when a goal is missed")
    parser.add_argument("--no-progress", action="store_true", help="no progress bars on stderr")


def run_env(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """Run the env benchmark and print it on ``out`` (stdout); exit 1 only with ``--strict`` and a missed goal."""
    out = out if out is not None else sys.stdout
    report = env_speed.measure(
        args.episodes,
        args.resets,
        args.random_steps,
        args.seed,
        progress=not args.no_progress,
        obs_episodes=args.obs_episodes,
    )
    print(json.dumps(report, indent=2) if args.json else format_env_report(report), file=out)
    missed = [f["name"] for f in report["figures"] if f["met"] is False]
    return 1 if args.strict and missed else 0


def format_env_report(report: dict[str, Any]) -> str:
    """The env benchmark's figures as a table for people."""
    lines = [
        f"env benchmark: {report['env']} on PyBullet {report['pybullet']} (DIRECT), scenario {report['scenario']}, "
        f"{report['episodes']} episodes of the expert's plan, seed {report['seed']}, {report['wall_s']:.1f} s",
        "",
        f"{'figure':<58} {'value':>10}  {'unit':<11} {'goal':<13} {'met':<4} PyBullet floor",
        "-" * 130,
    ]
    for f in report["figures"]:
        value = f"{f['value']:,.0f}" if f["value"] >= 100 else f"{f['value']:.2f}"
        met = "-" if f["met"] is None else ("yes" if f["met"] else "NO")
        lines.append(
            f"{f['name']:<58} {value:>10}  {f['unit']:<11} {f['goal'] or '-':<13} {met:<4} {f['floor'] or '-'}"
        )
    counts = report["random_policy"]
    lines.append("")
    lines.append(
        f"random policy: {report['random_steps']} steps in {counts['episodes']} episodes, "
        f"{counts['invalid_actions']} invalid actions, {counts['collisions']} collisions, {counts['pushes']} pushes"
    )
    return "\n".join(lines)


# ---------------------------------------------------------------------------- bench planner
def _register_planner(bench: argparse._SubParsersAction) -> None:
    parser = PLANNER_COMMAND.add(bench, run_planner)
    _add_seed(parser, planner_speed.DEFAULT_SEED, "seed of every case's generator")
    parser.add_argument(
        "--scale",
        type=positive_float,
        default=1.0,
        metavar="X",
        help="multiply the scenarios per case (default 1: 20 per V-B area, 5 per V-C pattern and corridor, "
        "10 for 2 and 3 objects, 5 for 4 and 5, 3 for 6, 5 per covered case)",
    )
    parser.add_argument(
        "--only",
        nargs="+",
        metavar="GROUP",
        help="run only these groups ("
        + " ".join(g if " " not in g else f"'{g}'" for g in planner_speed.groups(planner_speed.cases()))
        + ")",
    )
    parser.add_argument(
        "--time-limit",
        type=positive_float,
        default=planner_speed.DEFAULT_TIME_LIMIT,
        metavar="S",
        help=f"seconds per planning call (default {planner_speed.DEFAULT_TIME_LIMIT:g})",
    )
    parser.add_argument(
        "--baseline",
        action="store_true",
        help="SCIP's default settings and no skeleton bounds (no Eq. 1, travel or action-window bounds, no "
        "conditional cuts); it still starts at the counting bound (not the paper's N = 3) and keeps the fewest-phase "
        "cuts, the counting delivery-timing cuts, the reachability check and the decoupled warm start",
    )
    parser.add_argument("--json", action="store_true", help="print every run and the summaries as JSON")


def _planner_rows(args: argparse.Namespace) -> list[planner_speed.Case]:
    """The cases ``--scale`` and ``--only`` choose; :class:`InputError` for an unknown group."""
    rows = planner_speed.cases(args.scale)
    if args.only:
        known = {c.group for c in rows}
        unknown = [g for g in args.only if g not in known]
        if unknown:
            raise InputError(f"unknown benchmark group(s) {', '.join(unknown)}; known: {', '.join(sorted(known))}")
        rows = [c for c in rows if c.group in args.only]
    return rows


def run_planner(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """Run the planner benchmark; exit status 0 when every plan is optimal and valid, 1 otherwise."""
    from expert.planner import solver_name  # here, so that the CLI starts without the solver

    out = out if out is not None else sys.stdout
    rows = _planner_rows(args)
    planner_speed.warm_up()
    options = planner_speed.BASELINE_OPTIONS if args.baseline else None
    started = time.perf_counter()
    runs: list[planner_speed.Run] = []
    for case in rows:
        runs.extend(planner_speed.run_case(case, args.seed, args.time_limit, options))
    wall = time.perf_counter() - started
    ok = all(r.status == "optimal" and r.valid for r in runs)
    if args.json:
        print(json.dumps(_planner_json(args, rows, runs, wall, solver_name()), indent=2), file=out)
        return 0 if ok else 1
    baseline = "baseline: SCIP defaults, no skeleton bounds, N from the counting bound"
    settings = baseline if args.baseline else "tuned settings"
    print(
        f"planner benchmark: {solver_name()}, {settings}, seed {args.seed}, {len(runs)} plans in {wall:.1f} s", file=out
    )
    print(file=out)
    print_tables(rows, runs, out)
    if not ok:
        bad = [
            f"{r.scenario} ({r.status}{', invalid' if not r.valid else ''})"
            for r in runs
            if r.status != "optimal" or not r.valid
        ]
        print(f"\nnot optimal or invalid: {', '.join(bad)}", file=out)
    return 0 if ok else 1


def _planner_json(
    args: argparse.Namespace, rows: list[planner_speed.Case], runs: list[planner_speed.Run], wall: float, solver: str
) -> dict[str, Any]:
    return {
        "solver": solver,
        "seed": args.seed,
        "baseline": bool(args.baseline),
        "wall_s": wall,
        "cases": {
            c.name: {**planner_speed.summary([r for r in runs if r.case == c.name]), "paper": c.paper} for c in rows
        },
        "runs": [asdict(r) for r in runs],
    }


def _ms(seconds: float) -> str:
    return f"{seconds * 1000:.0f}" if seconds >= 0.0095 else f"{seconds * 1000:.1f}"


def _goal(case: planner_speed.Case) -> str:
    if case.goal_median_s is None:
        return "-"
    text = f"median {_ms(case.goal_median_s)}"
    if case.goal_p95_s is not None:
        text += f", p95 {_ms(case.goal_p95_s)}"
    return text


def print_tables(rows: list[planner_speed.Case], runs: list[planner_speed.Run], out: TextIO) -> None:
    """The results table, the per-goal table and the time breakdown, in milliseconds."""
    _print_case_table(rows, runs, out)
    print(file=out)
    _print_goal_table(rows, runs, out)
    print(file=out)
    _print_time_shares(rows, runs, out)


def _print_case_table(rows: list[planner_speed.Case], runs: list[planner_speed.Run], out: TextIO) -> None:
    head = (
        f"{'case':<16} {'n':>3} {'median':>7} {'p95':>7} {'mean (SD)':>14} {'max':>7}  "
        f"{'statuses':<14} {'phases':<8} {'paper s mean (SD)':<18}"
    )
    print(head, file=out)
    print("-" * len(head), file=out)
    for case in rows:
        s = planner_speed.summary([r for r in runs if r.case == case.name])
        statuses = " ".join(f"{k} {v}" for k, v in sorted(s["statuses"].items()))
        phases = ",".join(str(p) for p in s["phases"])
        mean_sd = f"{_ms(s['mean_s'])} ({_ms(s['sd_s'])})"
        print(
            f"{case.name:<16} {s['count']:>3} {_ms(s['median_s']):>7} {_ms(s['p95_s']):>7} {mean_sd:>14} "
            f"{_ms(s['max_s']):>7}  {statuses:<14} {phases:<8} {case.paper:<18}",
            file=out,
        )
    print("(times in ms; paper in s)", file=out)


def _print_goal_table(rows: list[planner_speed.Case], runs: list[planner_speed.Run], out: TextIO) -> None:
    print(f"{'group':<8} {'n':>3} {'median':>7} {'p95':>7}  {'goal (ms)':<20} {'met':<4} {'optimal':>8}", file=out)
    for group in planner_speed.groups(rows):
        first = next(c for c in rows if c.group == group)
        s = planner_speed.summary([r for r in runs if r.group == group])
        met = {None: "-", True: "yes", False: "no"}[planner_speed.goal_met(first, s)]
        optimal = f"{s['statuses'].get('optimal', 0)}/{s['count']}"
        print(
            f"{group:<8} {s['count']:>3} {_ms(s['median_s']):>7} {_ms(s['p95_s']):>7}  {_goal(first):<20} {met:<4} "
            f"{optimal:>8}",
            file=out,
        )


def _print_time_shares(rows: list[planner_speed.Case], runs: list[planner_speed.Run], out: TextIO) -> None:
    print("where the time goes (share of the summed total_s):", file=out)
    print(
        f"{'group':<8} {'prepare+bound':>13} {'build':>7} {'prove N<N*':>10} {'solve N*':>9} {'other':>6} "
        f"{'extra N tried':>13}",
        file=out,
    )
    names = ("prepare_s", "build_s", "infeasible_solve_s", "final_solve_s", "other")
    for group in planner_speed.groups(rows):
        shares = planner_speed.time_shares([r for r in runs if r.group == group])
        text = " ".join(f"{100 * shares[n]:>{w}.0f}%" for n, w in zip(names, (12, 6, 9, 8, 5), strict=True))
        print(f"{group:<8} {text} {shares['extra_n_tried']:>13.2f}", file=out)


# ---------------------------------------------------------------------------- records of bench anytime and push
def _records(path: Path, command: str, keys: tuple[str, ...]) -> list[dict[str, Any]]:
    """The records of an earlier ``bench COMMAND --out``; :class:`InputError` names what is wrong."""
    check_readable(path, "records file")
    try:
        records = json.loads(path.read_text(encoding="utf-8"))
    except (UnicodeDecodeError, json.JSONDecodeError) as error:
        raise InputError(f"{path}: not JSON written by bench {command} --out ({error})") from None
    if not isinstance(records, list) or not all(isinstance(r, dict) and set(keys) <= r.keys() for r in records):
        raise InputError(f"{path}: not a list of bench {command} records (each with {', '.join(keys)})")
    return records


def _add_records_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", metavar="JSON", help="also write one record per planning call to this file")
    parser.add_argument(
        "--compare",
        metavar="JSON",
        help="records another checkout wrote with --out: summarised too, against this run's reference plans",
    )


# ---------------------------------------------------------------------------- bench anytime
def _register_anytime(bench: argparse._SubParsersAction) -> None:
    parser = ANYTIME_COMMAND.add(bench, run_bench_anytime)
    _add_records_options(parser)


def _echo_anytime_record(r: dict[str, Any]) -> None:
    echo(f"{r['group']} #{r['index']} limit {r['limit']:g} s: {r['status']}, {r['seconds']:.3f} s", file=sys.stderr)


def run_bench_anytime(args: argparse.Namespace) -> int:
    out = Path(args.out) if args.out else None
    if out is not None:
        check_writable(out, "records file")
    other = _records(Path(args.compare), "anytime", anytime_speed.RECORD_KEYS) if args.compare else None
    records = anytime_speed.measure(report=_echo_anytime_record)
    if out is not None:
        out.write_text(json.dumps(records, indent=1), encoding="utf-8")
    print("this run:")
    print("\n".join(anytime_speed.summary(records, records)))
    if other is not None:
        print(f"\n{args.compare} (against this run's reference plans):")
        print("\n".join(anytime_speed.summary(other, records)))
    return 0


# ---------------------------------------------------------------------------- bench push
def _register_push(bench: argparse._SubParsersAction) -> None:
    parser = PUSH_COMMAND.add(bench, run_bench_push)
    parser.add_argument("--out", metavar="JSON", help="also write one record per scenario to this file")
    parser.add_argument(
        "--compare", metavar="JSON", help="records another checkout wrote with --out: compared scenario by scenario"
    )


def run_bench_push(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """Print the push table, and with ``--compare`` the comparison with the other records."""
    out = out if out is not None else sys.stdout
    path = Path(args.out) if args.out else None
    if path is not None:
        check_writable(path, "records file")
    before = _records(Path(args.compare), "push", push_speed.RECORD_KEYS) if args.compare else None
    records = push_speed.measure()
    if path is not None:
        path.write_text(json.dumps(records, indent=1), encoding="utf-8")
    print("\n".join(push_speed.summary(records)), file=out)
    if before is not None:
        print("\n" + "\n".join(push_speed.compare(records, before)), file=out)
    return 0


# ---------------------------------------------------------------------------- bench generate
def _register_generate(bench: argparse._SubParsersAction) -> None:
    from training.evaluation.expert import DEFAULT_FAMILIES

    parser = GENERATE_COMMAND.add(bench, run_bench_generate)
    parser.add_argument(
        "--families",
        default=",".join(DEFAULT_FAMILIES),
        metavar="A,B",
        help=f"comma-separated families (default {','.join(DEFAULT_FAMILIES)})",
    )
    parser.add_argument("--seed", type=seed, default=0, metavar="N", help="episode k uses seed N + k (default 0)")
    parser.add_argument(
        "--policy", choices=("expert", "random"), default="expert", help="the MILP expert (default) or random"
    )
    parser.add_argument("--time-limit", type=positive_float, default=10.0, metavar="S", help="per planning call")
    parser.add_argument("--episodes", type=positive_int, default=100, metavar="N", help="episodes per run")
    parser.add_argument(
        "--workers", type=positive_int, nargs="+", default=[1, 2], metavar="W", help="worker counts (default 1 2)"
    )
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")


def run_bench_generate(args: argparse.Namespace) -> int:
    rows = []
    for family in families(args.families):
        source = EpisodeSource(family=family, seed=args.seed, policy=args.policy, time_limit=args.time_limit)
        rows += generate_speed.generation(source, args.episodes, args.workers)
    if args.json:
        print(json.dumps({"policy": args.policy, "episodes": args.episodes, "runs": rows}, indent=2))
        return 0
    print(f"policy {args.policy}, {args.episodes} episodes per run (seeds {args.seed}..), process pool")
    header = (
        f"{'family':<9} {'workers':>7} {'ep/s':>7} {'ep/s/worker':>11} {'plan s/ep':>9} {'policy s/ep':>11} "
        f"{'sim s/ep':>8} {'plan %':>6} {'speed-up':>8}"
    )
    print(header)
    print("-" * len(header))
    for row in rows:
        print(
            f"{row['family']:<9} {row['workers']:>7} {row['episodes_per_s']:>7.2f} "
            f"{row['episodes_per_s_per_worker']:>11.2f} {row['planning_s_per_episode']:>9.4f} "
            f"{row['policy_s_per_episode']:>11.4f} {row['simulation_s_per_episode']:>8.4f} "
            f"{100 * row['planning_share']:>6.1f} {row['speed_up']:>8.2f}"
        )
    return 0


# ---------------------------------------------------------------------------- bench phases
PHASE_FAMILIES = "basic,push,corridor,multi-2"


def _register_phases(bench: argparse._SubParsersAction) -> None:
    parser = bench.add_parser(
        "phases",
        help="the candidate-phase interface: expert actions it expresses, its speed next to the plain env's",
        description="Run the MILP expert through FetchCarryPushPhases-v0 (seeds from 0) and print, per family, "
        "its success, how many of its actions an allowed candidate stands for (by mode, and whole episodes) and "
        "the time of the action mask; then the steps per second of a random masked policy over the candidates "
        "next to the random masked policy of FetchCarryPush-v0, measured in the same run (compare the ratio: "
        "the machine may be shared).",
    )
    parser.add_argument(
        "--families", default=PHASE_FAMILIES, metavar="A,B", help=f"comma-separated families (default {PHASE_FAMILIES})"
    )
    parser.add_argument(
        "--episodes", type=positive_int, default=100, metavar="N", help="expert episodes per family (default 100)"
    )
    parser.add_argument(
        "--steps", type=positive_int, default=1000, metavar="N", help="steps per speed figure (default 1000)"
    )
    parser.add_argument("--speed-only", action="store_true", help="only the speed table (no expert episodes)")
    parser.add_argument(
        "--split", action="store_true",
        help="also where each walk's time goes: resets, mask and step (phase env), resets, policy and step (plain)",
    )  # fmt: skip
    parser.set_defaults(handler=run_bench_phases)


def _load() -> str:
    """The load averages (1, 5, 15 minutes) as ``uptime`` prints them: the machine may be shared."""
    return ", ".join(f"{value:.2f}" for value in os.getloadavg())


def run_bench_phases(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """Print the expressibility table, then the speed table, of the candidate-phase interface."""
    from benchmarks.speed import phases as phases_speed  # here: it loads the planner, which --help does without

    out = out if out is not None else sys.stdout
    names = families(args.families)
    if not args.speed_only:
        _print_expressibility(names, args.episodes, out)
    print(
        f"speed ({args.steps} random masked steps per family; mask ms: mean and median per step; "
        f"ratio: plain / phases steps per second; load: the 1-minute load average after the family; the machine is "
        f"shared: compare the ratio; load at the start {_load()})",
        file=out,
    )
    print(
        f"{'family':10} {'phases steps/s':>15} {'mask ms':>8} {'median':>7} {'plain steps/s':>14} {'ratio':>6} "
        f"{'load':>5}  allowed steps refused",
        file=out,
    )
    for family in names:
        r = phases_speed.speed(family, args.steps)
        ratio = r["plain_steps_per_s"] / r["phases_steps_per_s"]
        print(
            f"{family:10} {r['phases_steps_per_s']:15.0f} {r['mask_ms']:8.2f} {r['mask_median_ms']:7.2f} "
            f"{r['plain_steps_per_s']:14.0f} {ratio:6.1f} {os.getloadavg()[0]:5.2f}  "
            f"{r['refused']}, stopped at a contact {r['contacts']}",
            file=out,
        )
    if args.split:
        _print_split(names, args.steps, out)
    return 0


def _print_split(names: tuple[str, ...], steps: int, out: TextIO) -> None:
    """Milliseconds per ``steps`` steps from seed 0, by part, of the phase env's walk and the plain env's."""
    from benchmarks.speed import phases as phases_speed

    print(f"\nwhere the time goes (ms per {steps} steps from seed 0; sample: ms per scenario drawn)", file=out)
    print(
        f"{'family':10} {'resets':>6} {'reset':>6} {'mask':>6} {'step':>6} {'total':>6}   "
        f"{'resets':>6} {'reset':>6} {'policy':>6} {'step':>6} {'total':>6}  {'sample':>6}",
        file=out,
    )
    for family in names:
        split = phases_speed.time_split(family, steps)
        p, q = split["phases"], split["plain"]
        p_total = p["reset"] + p["mask"] + p["step"]
        q_total = q["reset"] + q["policy"] + q["step"]
        print(
            f"{family:10} {p['resets']:6.0f} {p['reset']:6.0f} {p['mask']:6.0f} {p['step']:6.0f} {p_total:6.0f}   "
            f"{q['resets']:6.0f} {q['reset']:6.0f} {q['policy']:6.0f} {q['step']:6.0f} {q_total:6.0f}  "
            f"{split['sample_ms']:6.1f}",
            file=out,
        )


def _print_expressibility(names: tuple[str, ...], episodes: int, out: TextIO) -> None:
    """The expert's actions that a candidate stands for, per family (``episodes`` seeds from 0)."""
    from benchmarks.speed import phases as phases_speed

    print(f"expert actions expressible as candidates ({episodes} episodes per family, seeds from 0)", file=out)
    print(
        f"{'family':10} {'success':>8} {'actions':>8} {'expressible':>12} {'episodes':>9} {'mask ms':>8}  by mode",
        file=out,
    )
    for family in names:
        r = phases_speed.expressibility(family, episodes)
        modes = ", ".join(f"{m} {k}/{n}" for m, (k, n) in r["by_mode"].items())
        print(
            f"{family:10} {r['expert_success']:8.0%} {r['actions']:8d} {r['expressible']:12.1%} "
            f"{r['whole_episodes']:9.0%} {r['mask_ms']:8.2f}  {modes}",
            file=out,
        )
    print(file=out)


# ---------------------------------------------------------------------------- bench ppo
def _register_ppo(bench: argparse._SubParsersAction) -> None:
    parser = bench.add_parser(
        "ppo",
        help="MaskablePPO's training speed on the candidate phases: env steps per second with 1 and 2 envs",
        description="Train the ppo learner's model (scratch MLP actor, the published rollout, epochs and batch "
        "size) on one family for --steps env steps with each number of envs in --envs, and print the env steps "
        "per second of model.learn (rollouts and updates; no evaluation, no set-up) and of its rollouts alone, "
        "with the load average (the machine may be shared: compare the envs measured in one run). "
        "More than one env: one forked worker process each.",
    )
    parser.add_argument("--family", default="basic", metavar="NAME", help="scenario family (default basic)")
    parser.add_argument("--envs", default="1,2", metavar="N[,N...]", help="numbers of envs to time (default 1,2)")
    parser.add_argument(
        "--steps", type=positive_int, default=4096, metavar="N", help="env steps per figure (default 4096)"
    )
    parser.add_argument(
        "--n-steps", type=positive_int, default=256, metavar="N",
        help="env steps per rollout, over all envs (default 256, the published budget's)",
    )  # fmt: skip
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    parser.set_defaults(handler=run_bench_ppo)


def _env_counts(text: str) -> list[int]:
    """``1,2`` -> ``[1, 2]``; :class:`InputError` unless each is a whole number from 1 to ``MAX_ENVS``."""
    try:
        counts = [int(part) for part in text.split(",") if part.strip()]
    except ValueError:
        counts = []
    if not counts or not all(1 <= n <= MAX_ENVS for n in counts):
        raise InputError(f"--envs: expected numbers from 1 to {MAX_ENVS} separated by commas, got {text!r}")
    return counts


def run_bench_ppo(args: argparse.Namespace, out: TextIO | None = None) -> int:
    """Time MaskablePPO with each number of envs and print steps per second (or JSON)."""
    out = out if out is not None else sys.stdout
    check_family(args.family)
    counts = _env_counts(args.envs)
    started = _load()
    if max(counts) > args.n_steps:
        raise InputError(f"--envs: at most --n-steps ({args.n_steps}) envs")
    options = PPOOptions(n_steps=args.n_steps, batch_size=min(PPOOptions.batch_size, args.n_steps))
    results = [ppo_speed.ppo_speed(args.family, n, args.steps, options) for n in counts]
    if args.json:
        echo(json.dumps({"load_start": started, "results": [ppo_speed.as_row(r) for r in results]}, indent=2), out)
        return 0
    print(
        f"MaskablePPO on {args.family}, {args.steps} env steps per figure, rollouts of {args.n_steps} "
        f"(load at the start {started})",
        file=out,
    )
    print(f"{'envs':>4} {'steps':>6} {'seconds':>8} {'steps/s':>8} {'rollout steps/s':>16} {'load':>5}", file=out)
    for r in results:
        print(
            f"{r.envs:4d} {r.steps:6d} {r.seconds:8.1f} {r.steps_per_s:8.0f} {r.rollout_steps_per_s:16.0f} "
            f"{r.load:5.2f}",
            file=out,
        )
    return 0
