"""The training package's commands: ``rollout``, ``generate``, ``dataset info|replay``, ``demo``,
``evaluate-expert`` and ``bench generate``.

Registered into ``training/cli.py`` by :func:`register`. Exit statuses: 0 success; 1 a
negative answer (an episode that did not deliver everything, a replay that did not
reproduce, an expert below its success goal); 2 bad input (raised as ``UsageError``
and friends, turned into one short message by the CLI's ``main``).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from fetchcarry_env.arguments import positive_float, positive_int, whole_number
from fetchcarry_env.errors import UsageError

DEFAULT_DEMO_PICTURE = "episode.png"
DEFAULT_DEMO_SEED = 7  # a push-family scenario whose goal is covered by a block (push-aside needed)


def register(commands: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add this package's commands to the ``fetchcarry`` parser."""
    _register_rollout(commands)
    _register_generate(commands)
    _register_dataset(commands)
    _register_demo(commands)
    _register_evaluate(commands)
    _register_bench(bench)


# ---------------------------------------------------------------------------- helpers
def _add_source_arguments(parser: argparse.ArgumentParser, *, policy: bool = True) -> None:
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--scenario", metavar="FILE", help="one fixed scenario (fetchcarry-scenario/1 JSON)")
    source.add_argument("--family", metavar="NAME", help="random scenarios of this family (basic, push, ...)")
    parser.add_argument("--seed", type=whole_number, default=0, metavar="N", help="reset seed (default 0)")
    if policy:
        parser.add_argument(
            "--policy",
            choices=("expert", "random"),
            default="expert",
            help="the MILP expert (default) or the masked random policy",
        )
    parser.add_argument(
        "--time-limit",
        type=positive_float,
        default=10.0,
        metavar="S",
        help="seconds per planning call of the expert (default 10)",
    )


def _source(args: argparse.Namespace, policy: str | None = None):
    from training.generate import EpisodeSource

    scenario = None
    if args.scenario is not None:
        from fetchcarry_env.scenario import Scenario

        scenario = Scenario.load(args.scenario).to_dict()
    return EpisodeSource(
        family=args.family,
        scenario=scenario,
        seed=args.seed,
        policy=policy or args.policy,
        time_limit=args.time_limit,
    )


def _check_picture(path: str | None) -> Path | None:
    if path is None:
        return None
    from training.pictures import check_picture_path

    try:
        picture = check_picture_path(path)
    except ValueError as error:
        raise UsageError(str(error)) from None
    if not picture.parent.is_dir():
        raise UsageError(f"cannot write {picture}: folder {picture.parent} does not exist")
    return picture


def _figures_text(figures: Any, label: str, policy: str) -> str:
    lines = [
        f"scenario   {figures.scenario} ({label}, seed {figures.seed}), policy {policy}",
        f"outcome    {figures.outcome}: {figures.delivered}/{figures.objects} object(s) at the goal after "
        f"{figures.steps} steps, return {figures.episode_return:.2f}",
    ]
    if figures.failure is not None:
        lines.append(f"failure    {figures.failure}")
    lines += [
        f"motion     path {figures.path_length_m:.2f} m, contacts {figures.collisions}, "
        f"refused actions {figures.invalid_actions}",
        f"planning   {figures.planning_s:.3f} s in {figures.plans} plan(s), {figures.replans} replans, "
        f"{figures.repairs} repairs, {figures.planner_failures} failures"
        + ("" if figures.objective is None else f", objective {figures.objective:.3f}"),
        f"timings    policy {figures.policy_s:.3f} s (planning included), simulation {figures.simulation_s:.3f} s",
    ]
    return "\n".join(lines)


def _run_one(source: Any, picture: Path | None) -> Any:
    from training.generate import make_env, make_policy
    from training.rollout import run_episode

    if picture is None:
        env = make_env(source)
    else:
        from training.pictures import STILL_RENDER_SIZE, is_gif

        size = {} if is_gif(picture) else dict(zip(("width", "height"), STILL_RENDER_SIZE, strict=True))
        env = make_env(source, render_mode="rgb_array", **size)
    try:
        record = run_episode(env, make_policy(source, env, source.seed), source.seed, render=picture is not None)
    finally:
        env.close()
    if picture is not None:
        from training.pictures import save_episode_picture

        save_episode_picture(record, picture)
    return record


# ---------------------------------------------------------------------------- rollout
def _register_rollout(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "rollout",
        help="run one episode in the physics env and print its figures",
        description="Run one episode of FetchCarryPush-v0 (a fixed scenario, or a family's scenario drawn from "
        "the seed) with the expert or the random policy, and print its figures: objects delivered, steps, "
        "return, path length, contacts, invalid actions, planning time and replans.",
        epilog="Exit status: 0 every object delivered, 1 not, 2 bad input.",
    )
    _add_source_arguments(parser)
    parser.add_argument("--render", metavar="PICTURE", help="write the episode as a .gif (every state) or .png")
    parser.add_argument("--json", action="store_true", help="print the figures as one JSON object")
    parser.set_defaults(handler=run_rollout)


def run_rollout(args: argparse.Namespace) -> int:
    picture = _check_picture(args.render)
    source = _source(args)
    record = _run_one(source, picture)
    if args.json:
        print(json.dumps({**record.figures.to_dict(), "picture": str(picture) if picture else None}, indent=2))
    else:
        print(_figures_text(record.figures, source.label, source.policy))
        if picture is not None:
            print(f"picture    {picture}")
    return 0 if record.figures.success else 1


# ---------------------------------------------------------------------------- generate
def _register_generate(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "generate",
        help="generate a Minari dataset of episodes (resumable)",
        description="Generate a Minari dataset under MINARI_DATASETS_PATH (default ~/.minari/datasets), "
        "no network. Episode k uses seed SEED + k; every episode stores its seed and scenario JSON (episode "
        "metadata) and the planner's figures (per-step infos). Finished episodes are staged at once, so an "
        "interrupted run resumes where it stopped when the same command is run again. An existing dataset id "
        "is never overwritten without --overwrite.",
        epilog="Exit status: 0 the dataset is complete, 2 bad input (existing id, other options than a "
        "partial run), 130 interrupted (run again to resume).",
    )
    _add_source_arguments(parser)
    parser.add_argument("--episodes", type=positive_int, required=True, metavar="N", help="episodes in the dataset")
    parser.add_argument("--dataset-id", required=True, metavar="ID", help="Minari id, e.g. fetchcarry/push-expert-v0")
    parser.add_argument("--workers", type=positive_int, default=1, metavar="W", help="parallel workers (default 1)")
    parser.add_argument(
        "--backend",
        choices=("process", "ray"),
        default="process",
        help="a local process pool (default) or Ray (optional extra: pip install ray)",
    )
    parser.add_argument("--ray-address", metavar="ADDR", help="a Ray cluster to join (default: start a local one)")
    parser.add_argument("--overwrite", action="store_true", help="replace an existing dataset with this id")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--json", action="store_true", help="print the report as one JSON object")
    parser.set_defaults(handler=run_generate)


def run_generate(args: argparse.Namespace) -> int:
    from training.generate import GenerationConfig, generate
    from training.staging import Staging

    config = GenerationConfig(dataset_id=args.dataset_id, episodes=args.episodes, source=_source(args))
    try:
        report = generate(
            config,
            workers=args.workers,
            backend=args.backend,
            overwrite=args.overwrite,
            progress=not args.no_progress,
            ray_address=args.ray_address,
        )
    except KeyboardInterrupt:
        staged = len(Staging(config.dataset_id).staged())
        print(
            f"fetchcarry: interrupted: {staged} of {config.episodes} episodes are staged; "
            "run the same command again to resume",
            file=sys.stderr,
        )
        return 130
    from training.datasets import dataset_path

    summary = {
        "dataset_id": report.dataset_id,
        "path": str(dataset_path(report.dataset_id)),
        "episodes": report.episodes,
        "resumed": report.resumed,
        "generated": report.generated,
        "successes_generated": sum(f["success"] for f in report.figures),
        "workers": report.workers,
        "backend": report.backend,
        "wall_s": report.wall_s,
        "assembly_s": report.assembly_s,
        "planning_s": sum(f["planning_s"] for f in report.figures),
        "simulation_s": sum(f["simulation_s"] for f in report.figures),
    }
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        print(
            f"dataset {report.dataset_id}: {report.episodes} episodes ({report.resumed} resumed, "
            f"{report.generated} generated: {summary['successes_generated']} delivered everything) "
            f"in {report.wall_s:.1f} s with {report.workers} {report.backend} worker(s) "
            f"({report.assembly_s:.1f} s of it writing the dataset)\n"
            f"written to {summary['path']}"
        )
    return 0


# ---------------------------------------------------------------------------- dataset
def _register_dataset(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "dataset", help="inspect and replay Minari datasets", description="Inspect and replay Minari datasets."
    )
    actions = parser.add_subparsers(dest="dataset_command", metavar="ACTION", required=True)
    info = actions.add_parser(
        "info",
        help="summary of a dataset",
        description="Summary of a dataset: episodes, steps, env, policy, outcomes and the planner's figures.",
    )
    info.add_argument("dataset_id", metavar="ID")
    info.add_argument("--json", action="store_true", help="print the summary as one JSON object")
    info.set_defaults(handler=run_dataset_info)
    replay = actions.add_parser(
        "replay",
        help="replay an episode and check that the env reproduces it",
        description="Recover the env from the dataset, reset it with the episode's seed, check that it draws "
        "the recorded scenario, step the recorded actions and compare every observation and reward.",
        epilog="Exit status: 0 reproduced, 1 not reproduced, 2 bad input.",
    )
    replay.add_argument("dataset_id", metavar="ID")
    replay.add_argument("--episode", type=whole_number, required=True, metavar="K", help="episode index (0-based)")
    replay.add_argument("--json", action="store_true", help="print the report as one JSON object")
    replay.set_defaults(handler=run_dataset_replay)


def run_dataset_info(args: argparse.Namespace) -> int:
    from training.datasets import info

    summary = info(args.dataset_id)
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    source = f"family {summary['family']}" if summary["family"] else f"scenario {summary['scenario']}"
    outcomes = ", ".join(f"{k} {v}" for k, v in sorted(summary["outcomes"].items()))
    print(
        "\n".join(
            [
                f"dataset     {summary['dataset_id']} ({summary['path']}, {summary['size_mb']:.1f} MB)",
                f"env         {summary['env_id']} ({source}), seeds {summary['seeds'][0]}..{summary['seeds'][1]}",
                f"policy      {summary['algorithm']}",
                f"episodes    {summary['episodes']} ({summary['steps']} steps, "
                f"{summary['mean_steps']:.1f} per episode)",
                f"outcomes    {outcomes}; success rate {summary['success_rate']:.1%}",
                f"planning    {summary['mean_planning_s']:.3f} s per episode (max {summary['max_planning_s']:.2f} s), "
                f"{summary['replans']} replans, {summary['repairs']} repairs, "
                f"{summary['planner_failures']} planner failures",
            ]
        )
    )
    return 0


def run_dataset_replay(args: argparse.Namespace) -> int:
    from training.datasets import replay

    report = replay(args.dataset_id, args.episode)
    if args.json:
        print(json.dumps(report.to_dict(), indent=2))
    else:
        verdict = "reproduced" if report.reproduced else "NOT reproduced"
        divergence = "" if report.first_divergence is None else f", first divergence at state {report.first_divergence}"
        print(
            f"episode {report.episode} of {report.dataset_id} (seed {report.seed}, {report.steps} steps): {verdict}\n"
            f"scenario {'same' if report.same_scenario else 'DIFFERENT'}, rewards "
            f"{'same' if report.same_rewards else 'DIFFERENT'}, largest observation difference "
            f"{report.max_observation_error:.2e}{divergence}"
        )
    return 0 if report.reproduced else 1


# ---------------------------------------------------------------------------- demo
def _register_demo(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "demo",
        help="the expert delivers an object whose goal is covered: a picture and the figures",
        description="Make FetchCarryPush-v0 with a push-family scenario (the goal is covered by clutter that "
        "must be pushed aside), run the MILP expert in the physics env, write a picture of the episode "
        "(.png: key states; .gif: every state) and print the episode's figures.",
        epilog="Exit status: 0 every object delivered, 1 not, 2 bad input.",
    )
    parser.add_argument("--out", default=DEFAULT_DEMO_PICTURE, metavar="PICTURE", help="picture to write")
    parser.add_argument("--seed", type=whole_number, default=DEFAULT_DEMO_SEED, metavar="N", help="the scenario's seed")
    parser.add_argument("--scenario", metavar="FILE", help="a scenario file instead of the push family")
    parser.add_argument("--time-limit", type=positive_float, default=10.0, metavar="S", help=argparse.SUPPRESS)
    parser.add_argument("--json", action="store_true", help="print the figures as one JSON object")
    parser.set_defaults(handler=run_demo, family=None)


def run_demo(args: argparse.Namespace) -> int:
    picture = _check_picture(args.out)
    if args.scenario is None:
        args.family = "push"
    source = _source(args, policy="expert")
    record = _run_one(source, picture)
    if args.json:
        print(json.dumps({**record.figures.to_dict(), "picture": str(picture)}, indent=2))
    else:
        print(_figures_text(record.figures, source.label, "expert"))
        print(f"picture    {picture}")
    return 0 if record.figures.success else 1


# ---------------------------------------------------------------------------- evaluate-expert
def _register_evaluate(commands: argparse._SubParsersAction) -> None:
    from training.evaluate_expert import DEFAULT_FAMILIES

    parser = commands.add_parser(
        "evaluate-expert",
        help="success rate and speed of the expert in physics, per family",
        description="Run the MILP expert on seeded scenarios of each family in the physics env, report the "
        "success rate, replans, planning and simulation time and episodes per second per worker, and write "
        "every failure as a scenario file plus a sidecar with its seed and figures.",
        epilog="Exit status: 0 every family at or above the success goal (99%), 1 not, 2 bad input.",
    )
    parser.add_argument(
        "--families",
        default=",".join(DEFAULT_FAMILIES),
        metavar="A,B",
        help=f"comma-separated families (default {','.join(DEFAULT_FAMILIES)})",
    )
    parser.add_argument("--episodes", type=positive_int, default=500, metavar="N", help="per family (default 500)")
    parser.add_argument(
        "--seed", type=whole_number, default=0, metavar="N", help="episode k uses seed N + k (default 0)"
    )
    parser.add_argument("--start", type=whole_number, default=0, metavar="K", help="first episode index (default 0)")
    parser.add_argument("--workers", type=positive_int, default=1, metavar="W", help="parallel workers (default 1)")
    parser.add_argument("--time-limit", type=positive_float, default=10.0, metavar="S", help="per planning call")
    parser.add_argument("--failures-dir", metavar="DIR", help="write failed scenarios and their sidecars here")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.set_defaults(handler=run_evaluate)


def _families(text: str) -> tuple[str, ...]:
    from fetchcarry_env.families import FAMILY_NAMES

    names = tuple(name.strip() for name in text.split(",") if name.strip())
    unknown = [name for name in names if name not in FAMILY_NAMES]
    if not names or unknown:
        raise UsageError(f"unknown family {', '.join(unknown) or '(none)'}: choose from {', '.join(FAMILY_NAMES)}")
    return names


def run_evaluate(args: argparse.Namespace) -> int:
    from training.evaluate_expert import SUCCESS_GOAL, evaluate_expert, results_table

    results = evaluate_expert(
        _families(args.families),
        episodes=args.episodes,
        seed=args.seed,
        start=args.start,
        workers=args.workers,
        time_limit=args.time_limit,
        failures_dir=Path(args.failures_dir) if args.failures_dir else None,
        progress=not args.no_progress,
    )
    if args.json:
        print(json.dumps([r.to_dict() for r in results], indent=2))
    else:
        print(results_table(results))
        for result in results:
            for failure in result.failures:
                print(f"failed: {failure['family']} seed {failure['seed']}: {failure['outcome']} ({failure['replay']})")
    return 0 if all(r.success_rate >= SUCCESS_GOAL for r in results) else 1


# ---------------------------------------------------------------------------- bench generate
def _register_bench(bench: argparse._SubParsersAction) -> None:
    from training.evaluate_expert import DEFAULT_FAMILIES

    parser = bench.add_parser(
        "generate",
        help="episodes per second per worker, planning vs simulation, speed-up with more workers",
        description="Run the same seeded expert episodes of each family with each worker count (the process "
        "pool of dataset generation, start-up included) and print episodes per second, episodes per second "
        "per worker, the seconds per episode in the planner, in the rest of the policy and in the simulation, "
        "and the speed-up over the first worker count.",
    )
    parser.add_argument(
        "--families",
        default=",".join(DEFAULT_FAMILIES),
        metavar="A,B",
        help=f"comma-separated families (default {','.join(DEFAULT_FAMILIES)})",
    )
    parser.add_argument(
        "--seed", type=whole_number, default=0, metavar="N", help="episode k uses seed N + k (default 0)"
    )
    parser.add_argument(
        "--policy", choices=("expert", "random"), default="expert", help="the MILP expert (default) or random"
    )
    parser.add_argument("--time-limit", type=positive_float, default=10.0, metavar="S", help="per planning call")
    parser.add_argument("--episodes", type=positive_int, default=100, metavar="N", help="episodes per run")
    parser.add_argument(
        "--workers", type=positive_int, nargs="+", default=[1, 2], metavar="W", help="worker counts (default 1 2)"
    )
    parser.add_argument("--json", action="store_true", help="print the figures as JSON")
    parser.set_defaults(handler=run_bench_generate)


def run_bench_generate(args: argparse.Namespace) -> int:
    from training.generate import EpisodeSource, bench_generation

    rows = []
    for family in _families(args.families):
        source = EpisodeSource(family=family, seed=args.seed, policy=args.policy, time_limit=args.time_limit)
        rows += bench_generation(source, args.episodes, args.workers)
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
