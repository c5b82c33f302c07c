"""The dataset commands: ``fetchcarry generate`` and ``fetchcarry dataset info|replay|render``.

Exit statuses: 0 success; 1 a replay that did not reproduce; 2 bad input (raised as
``InputError`` and friends, turned into one short message by :func:`training.cli.main`);
130 interrupted (``generate`` resumes when run again).
"""

from __future__ import annotations

import argparse
import json
import sys
from dataclasses import asdict
from pathlib import Path

from fetchcarry_env.errors import InputError
from fetchcarry_env.observations import get_mode, image_option_names, modes
from training.cli.arguments import add_worker_options, positive_int, whole_number
from training.cli.commands import summary
from training.cli.episodes import add_obs_mode_argument, add_source_arguments, episode_source
from training.cli.exits import INTERRUPTED, ignore_unraisable, say
from training.cli.options import Command
from training.cli.text import echo
from training.data.datasets import dataset_path, info, replay
from training.data.generate import (
    DATASET_TIME_LIMIT,
    DatasetExistsError,
    GenerationConfig,
    GenerationReport,
    StagingMismatchError,
    generate,
)
from training.data.models import CollectionConfig, generate_models
from training.data.render import render_dataset
from training.data.staging import Staging, StagingError
from training.evaluation.protocol import refuse_split_scenario

GENERATE_COMMAND = Command(
    name="generate",
    help=summary("generate"),
    description="Generate a Minari dataset under MINARI_DATASETS_PATH (default ~/.minari/datasets), "
    "no network. Episode k uses seed SEED + k; every episode stores its seed and scenario JSON (episode "
    "metadata) and the planner's figures (per-step infos). Finished episodes are staged at once, so an "
    "interrupted run resumes where it stopped when the same command is run again. An existing dataset id "
    "is never overwritten without --overwrite; with it, the new dataset replaces the old one only once it is "
    "whole. One run per dataset id at a time; a staged episode that cannot be read is set aside and made again. "
    "With --models --out DIR it writes no dataset but a collection of the planner's MILPs for the family's seeds "
    "(MPS, a JSON of the variables' meanings and the known optimum, the scenario and the plan per seed; an "
    "interrupted run keeps the seeds it finished and the same command resumes).",
    epilog="Exit status: 0 the dataset is complete (also when it already was, with the same options), 2 bad "
    "input (an existing id made with other options, a partial run with other options, another run working on "
    "the id, too little disk space), 130 interrupted (run the same command again to resume), 143 stopped by "
    "SIGTERM (the same).",
)


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``generate`` and ``dataset`` to the ``fetchcarry`` parser."""
    _add_generate_options(GENERATE_COMMAND.add(commands, run_generate))
    _register_dataset(commands)


# ---------------------------------------------------------------------------- generate
def _add_generate_options(parser: argparse.ArgumentParser) -> None:
    add_source_arguments(parser, time_limit=DATASET_TIME_LIMIT)  # a dataset refuses a plan the stop decided
    parser.add_argument("--episodes", type=positive_int, required=True, metavar="N", help="episodes in the dataset")
    parser.add_argument(
        "--interface",
        choices=("env", "phases"),
        default="env",
        help="record the env's own actions (FetchCarryPush-v0, default) or candidate phases "
        "(FetchCarryPushPhases-v0: actions are candidate indices, each state's mask is the per-step info "
        "action_mask; an expert move no candidate expresses is recorded as the nearest allowed move candidate and "
        "the expert plans again from where it left the robot; the per-step info projected marks those steps)",
    )
    parser.add_argument(
        "--dataset-id", metavar="ID", help="Minari id, e.g. fetchcarry/push-expert-v0 (required without --models)"
    )
    parser.add_argument(
        "--models",
        action="store_true",
        help="instead of a dataset, write the MILPs the planner solves for each of the family's seeds into --out: "
        "per seed its scenario, the plan and each phase count's model as MPS with a JSON of its variables and the "
        "optimum SCIP proved (--time-limit is per scenario; resumable like a dataset)",
    )
    parser.add_argument("--out", metavar="DIR", help="with --models: the collection's folder (made if missing)")
    add_worker_options(parser)
    parser.add_argument("--overwrite", action="store_true", help="replace an existing dataset with this id")
    parser.add_argument(
        "--allow-evaluation-seeds",
        action="store_true",
        help="allow seeds from 10^9 (the benchmark's) and a split's scenario as --scenario: research on purpose "
        "(refused by default, exit 2, so that no one trains on what is reported)",
    )
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--json", action="store_true", help="print the report as one JSON object")


def run_generate(args: argparse.Namespace) -> int:
    """``fetchcarry generate``: 0 the dataset is complete, 130 interrupted (what is staged is kept)."""
    if args.models:
        return run_generate_models(args)
    if args.dataset_id is None:
        raise InputError("give --dataset-id ID (or --models --out DIR for a collection of MILPs)")
    if args.out is not None:
        raise InputError("--out is for --models; a dataset goes to --dataset-id")
    config = GenerationConfig(dataset_id=args.dataset_id, episodes=args.episodes, source=episode_source(args))
    if config.source.scenario is not None:
        refuse_split_scenario(config.source.scenario, args.allow_evaluation_seeds)
    try:
        report = generate(
            config,
            workers=args.workers,
            backend=args.backend,
            overwrite=args.overwrite,
            progress=not args.no_progress,
            ray_address=args.ray_address,
            allow_evaluation_seeds=args.allow_evaluation_seeds,
        )
    except KeyboardInterrupt:
        sys.unraisablehook = ignore_unraisable  # see training.cli.exits.run_command
        staged = len(Staging(config.dataset_id).staged())
        say(f"interrupted: {staged} of {config.episodes} episodes are staged; run the same command again to resume")
        return INTERRUPTED
    except DatasetExistsError as error:
        raise InputError(f"{error}: choose another id, or pass --overwrite to replace it") from None
    except StagingMismatchError as error:
        raise InputError(
            f"{error}: run the same command as before to resume it, or pass --overwrite to start again"
        ) from None
    except StagingError as error:
        raise InputError(f"{error}; pass --overwrite to start the dataset again") from None
    for file in report.set_aside:
        say(f"warning: the staged episode {file} could not be read: set aside in its folder's corrupt/ and made again")
    _print_generation(report, args.json)
    return 0


def run_generate_models(args: argparse.Namespace) -> int:
    """``fetchcarry generate --models``: 0 the collection is complete, 130 interrupted (finished seeds are kept)."""
    if args.family is None:
        raise InputError("--models takes --family NAME (a collection is made of a family's seeds)")
    if args.out is None:
        raise InputError("--models writes into a folder: give --out DIR")
    if args.dataset_id is not None:
        raise InputError("--models writes no dataset: give --out DIR, not --dataset-id")
    config = CollectionConfig(args.family, args.seed, args.episodes, args.time_limit)
    try:
        report = generate_models(
            config, Path(args.out), progress=not args.no_progress, allow_evaluation_seeds=args.allow_evaluation_seeds
        )
    except KeyboardInterrupt:
        sys.unraisablehook = ignore_unraisable  # see training.cli.exits.run_command
        say(f"interrupted: the seeds finished are kept in {args.out}; run the same command again to resume")
        return INTERRUPTED
    summary = {
        "out": str(report.out),
        "family": config.family,
        "seeds": [config.seed, config.seed + config.episodes - 1],
        "resumed": report.resumed,
        "generated": report.generated,
        "models": report.models,
        "proven_optimal": report.proven,
        "wall_s": report.wall_s,
    }
    if args.json:
        print(json.dumps(summary, indent=2))
    else:
        echo(
            f"collection of {config.family}, seeds {config.seed}..{config.seed + config.episodes - 1}: "
            f"{config.episodes} scenarios ({report.resumed} resumed, {report.generated} planned now), "
            f"{report.models} models, {report.proven} scenarios proven optimal, in {report.wall_s:.1f} s\n"
            f"written to {report.out} (index: {report.out / 'collection.json'})"
        )
    return 0


def _print_generation(report: GenerationReport, as_json: bool) -> None:
    """What ``generate`` did, as text or as one JSON object."""
    if report.already_complete:
        message = f"dataset {report.dataset_id} is already complete ({report.episodes} episodes): nothing to do"
        if as_json:
            print(json.dumps({"dataset_id": report.dataset_id, "already_complete": True, "message": message}))
        else:
            echo(f"{message}\nit is in {dataset_path(report.dataset_id)}")
        return
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
        "set_aside": report.set_aside,
        "already_complete": False,
    }
    if as_json:
        print(json.dumps(summary, indent=2))
    else:
        echo(
            f"dataset {report.dataset_id}: {report.episodes} episodes ({report.resumed} resumed, "
            f"{report.generated} generated: {summary['successes_generated']} delivered everything) "
            f"in {report.wall_s:.1f} s with {report.workers} {report.backend} worker(s) "
            f"({report.assembly_s:.1f} s of it writing the dataset)\n"
            f"written to {summary['path']}"
        )


# ---------------------------------------------------------------------------- dataset
def _register_dataset(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser("dataset", help=summary("dataset"), description="Inspect and replay Minari datasets.")
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
    _register_render(actions)


def _register_render(actions: argparse._SubParsersAction) -> None:
    render = actions.add_parser(
        "render",
        help="replay a dataset into another observation mode (topdown maps, RGB-D images)",
        description="Replay every episode of dataset ID in an env of the same id and options in --obs-mode, from "
        "its seed and recorded actions, check that the state and rewards are the recorded ones exactly, and write "
        "the new dataset NEW_ID: the same actions, rewards, infos and episode metadata, the new observations.",
        epilog="Exit status: 0 rendered, 2 bad input (an unknown or broken dataset, an episode that does not replay "
        "exactly, NEW_ID exists without --overwrite), 130 interrupted (nothing is written).",
    )
    render.add_argument("dataset_id", metavar="ID")
    add_obs_mode_argument(render, "the observation of the new dataset")
    render.add_argument("--out", required=True, metavar="NEW_ID", help="the new dataset's Minari id")
    for mode in modes():
        for option in mode.options:
            render.add_argument(
                "--" + option.name.replace("_", "-"),
                type=option.kind,
                choices=option.choices or None,
                metavar=None if option.choices else "X",
                help=f"--obs-mode {mode.name}: {option.help}"
                + ("" if option.default is None else f" (default {option.default})"),
            )
    render.add_argument("--overwrite", action="store_true", help="replace an existing NEW_ID")
    render.add_argument("--no-progress", action="store_true", help="no progress bar")
    render.add_argument("--json", action="store_true", help="print the report as one JSON object")
    render.set_defaults(handler=run_dataset_render)


def run_dataset_render(args: argparse.Namespace) -> int:
    """``fetchcarry dataset render``: 0 rendered (bad input raises)."""
    options = {k: getattr(args, k) for k in image_option_names() if getattr(args, k) is not None}
    wrong = [k for k in options if k not in get_mode(args.obs_mode).option_names]
    if wrong:
        flags = ", ".join("--" + k.replace("_", "-") for k in wrong)
        raise InputError(f"{flags} do(es) not apply to --obs-mode {args.obs_mode}")
    report = render_dataset(
        args.dataset_id, args.obs_mode, args.out, image_options=options, overwrite=args.overwrite,
        progress=not args.no_progress,
    )  # fmt: skip
    if args.json:
        print(json.dumps(asdict(report), indent=2))
    else:
        echo(
            f"dataset {report.dataset_id}: {report.episodes} episodes ({report.steps} steps) of {report.source_id} "
            f"rendered into obs_mode {report.obs_mode} in {report.wall_s:.1f} s, {report.size_mb:.1f} MB\n"
            f"written to {dataset_path(report.dataset_id)}"
        )
    return 0


def run_dataset_info(args: argparse.Namespace) -> int:
    """``fetchcarry dataset info``: 0."""
    summary = info(args.dataset_id)
    if args.json:
        print(json.dumps(summary, indent=2))
        return 0
    source = f"family {summary['family']}" if summary["family"] else f"scenario {summary['scenario']}"
    outcomes = ", ".join(f"{k} {v}" for k, v in sorted(summary["outcomes"].items()))
    echo(
        "\n".join(
            [
                f"dataset     {summary['dataset_id']} ({summary['path']}, {summary['size_mb']:.1f} MB)",
                f"env         {summary['env_id']} ({source}), seeds {summary['seeds'][0]}..{summary['seeds'][1]}",
                f"policy      {summary['algorithm']}",
                f"episodes    {summary['episodes']} ({summary['steps']} steps, "
                f"{summary['mean_steps']:.1f} per episode)",
                f"outcomes    {outcomes}; success rate {summary['success_rate']:.1%}",
                f"planning    {summary['plans']} plans, "
                f"{summary['replans']} replans, {summary['repairs']} repairs, "
                f"{summary['planner_failures']} planner failures",
                *(
                    [
                        f"projected   {summary['projected_moves']} expert moves recorded as their nearest move "
                        f"candidate ({summary['projected_moves'] / summary['episodes']:.2f} per episode)"
                    ]
                    if summary["projected_moves"] is not None
                    else []
                ),
            ]
        )
    )
    return 0


def run_dataset_replay(args: argparse.Namespace) -> int:
    """``fetchcarry dataset replay``: 0 the episode is reproduced, 1 not."""
    report = replay(args.dataset_id, args.episode)
    if args.json:
        print(json.dumps(report.to_dict(), indent=2))
    else:
        verdict = "reproduced" if report.reproduced else "NOT reproduced"
        divergence = "" if report.first_divergence is None else f", first divergence at state {report.first_divergence}"
        echo(
            f"episode {report.episode} of {report.dataset_id} (seed {report.seed}, {report.steps} steps): {verdict}\n"
            f"scenario {'same' if report.same_scenario else 'DIFFERENT'}, rewards "
            f"{'same' if report.same_rewards else 'DIFFERENT'}, largest observation difference "
            f"{report.max_observation_error:.2e}{divergence}"
        )
    return 0 if report.reproduced else 1
