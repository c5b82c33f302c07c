"""The episode commands: ``fetchcarry rollout``, ``fetchcarry demo`` and ``fetchcarry evaluate-expert``.

Exit statuses: 0 success; 1 a negative answer (an episode that did not deliver
everything, an expert below its success goal); 2 bad input (raised as ``InputError``
and friends, turned into one short message by :func:`training.cli.main`).
"""

from __future__ import annotations

import argparse
import json
from dataclasses import replace
from pathlib import Path
from typing import Any

from expert.plans import plan_length
from fetchcarry_env.errors import InputError
from fetchcarry_env.families import FAMILY_NAMES
from fetchcarry_env.kinematics import WAIT_COST
from fetchcarry_env.observations import mode_names, modes
from training.cli.arguments import capacity_text, non_negative_int, positive_float, positive_int
from training.cli.commands import summary
from training.cli.exits import INTERRUPTED, say
from training.cli.files import check_picture, load_plan, load_scenario
from training.cli.seeds import check_seed_range, seed
from training.cli.text import echo
from training.data.sources import EpisodeSource
from training.evaluation.expert import (
    DEFAULT_FAMILIES,
    SUCCESS_GOAL,
    EvaluationInterrupted,
    evaluate_expert,
    results_table,
)
from training.pictures.files import render_size
from training.resolve import check_run_obs_mode, run_image_options
from training.rollout import run_episode

DEFAULT_DEMO_PICTURE = "episode.png"
DEFAULT_DEMO_SEED = 7  # a push-family scenario whose goal is covered by a block (push-aside needed)


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``rollout``, ``demo`` and ``evaluate-expert`` to the ``fetchcarry`` parser."""
    _register_rollout(commands)
    _register_demo(commands)
    _register_evaluate(commands)


# ---------------------------------------------------------------------------- helpers
def add_source_arguments(
    parser: argparse.ArgumentParser, *, policy: bool = True, runs: bool = False, time_limit: float = 10.0
) -> None:
    """``--scenario``/``--family``, ``--seed``, ``--policy`` and ``--time-limit``: where episodes come from.

    With ``runs``, ``--policy`` also takes a run folder of ``fetchcarry train``. ``time_limit``
    is the default safety stop of each planning call, seconds.
    """
    source = parser.add_mutually_exclusive_group(required=True)
    source.add_argument("--scenario", metavar="FILE", help="one fixed scenario (fetchcarry-scenario/1 JSON)")
    source.add_argument("--family", metavar="NAME", help="random scenarios of this family (basic, push, ...)")
    parser.add_argument("--seed", type=seed, default=0, metavar="N", help="reset seed (default 0)")
    if policy and runs:
        parser.add_argument(
            "--policy",
            default="expert",
            metavar="POLICY",
            help="expert (the MILP expert, default), random (the masked random policy) or RUN_DIR (a run folder "
            "of fetchcarry train: bc, dagger or ppo, acting in the candidate phases)",
        )
    elif policy:
        parser.add_argument(
            "--policy",
            choices=("expert", "random"),
            default="expert",
            help="the MILP expert or the masked random policy (default expert)",
        )
    parser.add_argument(
        "--time-limit",
        type=positive_float,
        default=time_limit,
        metavar="S",
        help=f"seconds per planning call of the expert: a safety stop, its plan is decided by a budget of SCIP "
        f"nodes (the same at any load) unless this stop comes first (default {time_limit:g})",
    )
    parser.add_argument(
        "--capacity",
        type=capacity_text,
        metavar="K=N,...",
        help="the observation's slots, e.g. objects=8,clutter=12 (the other counts the default's: objects 4, "
        "clutter 8, tables 6, obstacles 12, postures 4); default: the family's, which holds every scenario it "
        "draws, or for --scenario the default grown to hold it",
    )
    add_obs_mode_argument(parser, default=None if runs else "state")  # None: a run folder's own mode


def add_obs_mode_argument(
    parser: argparse.ArgumentParser, meaning: str = "the env's observation", default: str | None = "state"
) -> None:
    """``--obs-mode``: ``state`` (default), ``topdown``, ``rgbd`` or a registered mode (docs/observations.md).

    ``default`` None tells a command that the option was left out (a run folder's own mode applies).
    """
    parser.add_argument(
        "--obs-mode",
        choices=mode_names(),
        default=default,
        help=f"{meaning}: " + ", ".join(f"{mode.name} ({mode.description})" for mode in modes()),
    )


def episode_source(args: argparse.Namespace, policy: str | None = None) -> EpisodeSource:
    """The ``EpisodeSource`` the options of :func:`add_source_arguments` describe."""
    scenario = None if args.scenario is None else load_scenario(Path(args.scenario)).to_dict()
    policy = policy or args.policy
    if policy not in ("expert", "random"):
        raise InputError(f"unknown policy {policy!r}: give expert, random or a run folder of fetchcarry train")
    return EpisodeSource(
        family=args.family,
        scenario=scenario,
        seed=args.seed,
        policy=policy,
        time_limit=args.time_limit,
        interface=getattr(args, "interface", "env"),
        capacity=getattr(args, "capacity", None),
        obs_mode=getattr(args, "obs_mode", None) or "state",
    )


def _figures_text(figures: Any, label: str, policy: str, time_limit: float) -> str:
    lines = [
        f"scenario   {figures.scenario} ({label}, seed {figures.seed}), policy {policy}",
        f"outcome    {figures.outcome}: {figures.delivered}/{figures.objects} object(s) at the goal after "
        f"{figures.steps} steps",
    ]
    if figures.failure is not None:
        lines.append(f"failure    {figures.failure}")
        why = failure_reason(figures.failure, time_limit)
        if why is not None:
            lines.append(f"why        {why}")
    lines += return_and_objective(figures)
    lines += [
        f"motion     path {figures.path_length_m:.2f} m, collisions {figures.collisions}, "
        f"invalid actions {figures.invalid_actions}",
        *(
            [
                f"planning   {figures.planning_s:.3f} s in {figures.plans} plan(s), {figures.replans} replans, "
                f"{figures.repairs} repairs, {figures.planner_failures} failures"
            ]
            if figures.plans
            else []
        ),
        f"timings    policy {figures.policy_s:.3f} s (planning included), simulation {figures.simulation_s:.3f} s",
    ]
    return "\n".join(lines)


def return_and_objective(figures: Any) -> list[str]:
    """The episode's return and the planner's objective: the same quantity, the task cost, seen from each side.

    The return is the env's reward summed: minus the episode's task cost (its travel cost,
    ``WAIT_COST`` per object for every phase it is not yet at its goal, and 1 per collision
    or refused action). The objective is the task cost of the expert's first plan, which
    the planner minimises: the return is minus it when the episode follows that plan.
    """
    lines = [
        f"return     {figures.episode_return:.2f} (the env's rewards summed: minus the episode's task cost, "
        f"its travel, {WAIT_COST:g} per object for each phase before it reached its goal, and penalties)"
    ]
    if figures.objective is not None:
        lines.append(
            f"objective  {figures.objective:.3f} (the task cost of the first plan, which the planner minimises; "
            "the return is minus it when the episode follows that plan)"
        )
        lines.append(f"plan       {plan_status_text(figures)}")
    return lines


def plan_status_text(figures: Any) -> str:
    """What the episode's plans were proven to be: the first plan's status, and the unproven fallback plans."""
    meaning = {
        "optimal": "optimal (proven by the planner)",
        "feasible": "feasible: a valid plan, not proven optimal",
    }.get(figures.plan_status, str(figures.plan_status))
    text = f"the first plan is {meaning}"
    if figures.fallback_plans:
        text += (
            f"; {figures.fallback_plans} of {figures.plans} planning call(s) ran out of time and were answered by "
            "the decoupled fallback plan (valid, not proven optimal)"
        )
    return text


def failure_reason(failure: str, time_limit: float) -> str | None:
    """Why an expert could not act, in words, from its failure message."""
    if failure.startswith("no plan (time_limit)"):
        return (
            f"the planner found no plan within its time limit of {time_limit:g} s per planning call "
            "(--time-limit gives it more)"
        )
    if failure.startswith("no plan (infeasible)"):
        return "the planner proved that no plan delivers every object from this state within the phases it tried"
    if failure.startswith("stuck"):
        return "the env would refuse the expert's next action and no nearby repair is allowed"
    return None


def _run_one(source: Any, picture: Path | None, run: Path | None = None, obs_mode: str | None = None) -> Any:
    """One episode of ``source`` (or of the run folder ``run``'s policy, in the candidate phases).

    ``obs_mode``: the ``--obs-mode`` given (None: left out); a run folder of an image network
    trained on another mode is refused (``BenchmarkError``, bad input).
    """
    options: dict[str, Any] = {}
    if run is not None:  # the run's network sees its own obs_mode
        options = dict(_run_spec_options(run))
        check_run_obs_mode(str(run), options.get("obs_mode"), obs_mode)
        source = replace(source, interface="phases", obs_mode=options.pop("obs_mode", source.obs_mode))
    if picture is None:
        env = source.build_env(**options)
    else:
        size = render_size(picture)
        env = source.build_env(render_mode="rgb_array", width=size[0], height=size[1], **options)
    try:
        policy = source.build_policy(env) if run is None else _load_run(run, env)
        record = run_episode(env, policy, source.seed, render=picture is not None)
    finally:
        env.close()
    if picture is not None:
        from training.pictures.episode import save_episode_picture  # matplotlib at its top

        save_episode_picture(record, picture)
    return record


def _run_spec_options(run: Path) -> dict[str, Any]:
    """The image options of run folder ``run``'s env (``obs_mode`` and the image size; none for the state)."""
    from training.learners.runs import read_config  # torch at its top

    return run_image_options(read_config(run))  # a broken config.json: a RunFolderError naming it


def _load_run(run: Path, env: Any) -> Any:
    """The policy of run folder ``run`` for ``env`` (a ``RunFolderError``, bad input, when it is not one)."""
    import torch  # torch only when a run folder is rolled out

    from training.learners.runs import load_policy  # torch at its top

    torch.set_num_threads(1)  # one decision at a time: a second thread made it about 60x slower here
    return load_policy(run, env)


def _run_folder(policy: str) -> Path | None:
    """The run folder ``--policy`` names, or None for ``expert`` and ``random``."""
    if policy in ("expert", "random"):
        return None
    path = Path(policy)
    if not path.is_dir():
        raise InputError(f"unknown policy {policy!r}: give expert, random or a run folder of fetchcarry train")
    return path


# ---------------------------------------------------------------------------- rollout
def _register_rollout(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "rollout",
        help=summary("rollout"),
        description="Run one episode of FetchCarryPush-v0 (a fixed scenario, or a family's scenario drawn from "
        "the seed) with the expert, the random policy or a trained run folder (in FetchCarryPushPhases-v0), "
        "and print its figures: objects delivered, steps, "
        "return, path length, collisions, invalid actions, planning time and replans; when the expert cannot "
        "act, why.",
        epilog="Exit status: 0 every object delivered, 1 not, 2 bad input.",
    )
    add_source_arguments(parser, runs=True)
    parser.add_argument(
        "--plan",
        metavar="PLAN",
        help="execute this saved plan (fetchcarry plan -o PLAN) in FetchCarryPush-v0 on --scenario, open loop: "
        "each phase after the start is one action, an action the env refuses counts as invalid and the next "
        "phase follows (instead of --policy)",
    )
    parser.add_argument("--render", metavar="PICTURE", help="write the episode as a .gif (every state) or .png")
    parser.add_argument("--json", action="store_true", help="print the figures as one JSON object")
    parser.set_defaults(handler=run_rollout)


def run_rollout(args: argparse.Namespace) -> int:
    picture = check_picture(args.render)
    if args.plan is not None:
        return _run_saved_plan(args, picture)
    run = _run_folder(args.policy)
    source = episode_source(args, policy="expert" if run is not None else None)
    record = _run_one(source, picture, run, args.obs_mode)
    label = source.policy if run is None else f"{run} (candidate phases)"
    return _report(args, record, picture, _figures_text(record.figures, source.label, label, source.time_limit))


def _run_saved_plan(args: argparse.Namespace, picture: Path | None) -> int:
    """``rollout --plan PLAN --scenario S``: the plan's phases as the env's actions (:class:`SavedPlanPolicy`)."""
    from training.policies.saved_plan import SavedPlanPolicy

    if args.scenario is None or args.policy != "expert" or args.obs_mode not in (None, "state"):
        raise InputError("--plan executes a saved plan on --scenario FILE (not a --family), without --policy")
    plan = load_plan(Path(args.plan))
    source = episode_source(args, policy="expert")
    scenario = load_scenario(Path(args.scenario))
    size = render_size(picture) if picture is not None else None
    env = source.build_env(**({"render_mode": "rgb_array", "width": size[0], "height": size[1]} if size else {}))
    try:
        policy = SavedPlanPolicy(plan, scenario, env.unwrapped.lattice)
        record = run_episode(env, policy, source.seed, render=picture is not None)
    finally:
        env.close()
    if picture is not None:
        from training.pictures.episode import save_episode_picture  # matplotlib at its top

        save_episode_picture(record, picture)
    text = _figures_text(record.figures, source.label, f"the saved plan {args.plan}", source.time_limit)
    return _report(args, record, picture, f"{text}\nplan file  {args.plan}: {plan_length(len(plan.phases))}")


def _report(args: argparse.Namespace, record: Any, picture: Path | None, text: str) -> int:
    """Print an episode's figures (``--json``: as one object), say where its picture is; 0 if it delivered all."""
    if args.json:
        print(json.dumps({**record.figures.to_dict(), "picture": str(picture) if picture else None}, indent=2))
    else:
        echo(text)
        if picture is not None:
            echo(f"picture    {picture}")
    return 0 if record.figures.success else 1


# ---------------------------------------------------------------------------- demo
def _register_demo(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "demo",
        help=summary("demo"),
        description="Make FetchCarryPush-v0 with a push-family scenario (the goal is covered by clutter that "
        "must be pushed aside), run the MILP expert in the physics env, write a picture of the episode "
        "(.png: key states; .gif: every state) and print the episode's figures.",
        epilog="Exit status: 0 every object delivered, 1 not, 2 bad input.",
    )
    parser.add_argument(
        "--out",
        default=DEFAULT_DEMO_PICTURE,
        metavar="PICTURE",
        help=f"picture to write: .png (key states) or .gif (every state) (default {DEFAULT_DEMO_PICTURE})",
    )
    parser.add_argument(
        "--seed",
        type=seed,
        default=DEFAULT_DEMO_SEED,
        metavar="N",
        help=f"the push-family scenario's seed (default {DEFAULT_DEMO_SEED}: its goal is covered by a block)",
    )
    parser.add_argument(
        "--scenario", metavar="FILE", help="a scenario file instead of the push family (default: the push family)"
    )
    parser.add_argument("--time-limit", type=positive_float, default=10.0, metavar="S", help=argparse.SUPPRESS)
    parser.add_argument("--json", action="store_true", help="print the figures as one JSON object")
    parser.set_defaults(handler=run_demo, family=None)


def run_demo(args: argparse.Namespace) -> int:
    picture = check_picture(args.out)
    if args.scenario is None:
        args.family = "push"
    source = episode_source(args, policy="expert")
    record = _run_one(source, picture)
    return _report(args, record, picture, _figures_text(record.figures, source.label, "expert", source.time_limit))


# ---------------------------------------------------------------------------- evaluate-expert
def _register_evaluate(commands: argparse._SubParsersAction) -> None:
    parser = commands.add_parser(
        "evaluate-expert",
        help=summary("evaluate-expert"),
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
    parser.add_argument("--seed", type=seed, default=0, metavar="N", help="episode k uses seed N + k (default 0)")
    parser.add_argument(
        "--start", type=non_negative_int, default=0, metavar="K", help="first episode index (default 0)"
    )
    parser.add_argument("--workers", type=positive_int, default=1, metavar="W", help="parallel workers (default 1)")
    parser.add_argument(
        "--time-limit", type=positive_float, default=10.0, metavar="S", help="seconds per planning call (default 10)"
    )
    parser.add_argument("--failures-dir", metavar="DIR", help="write failed scenarios and their sidecars here")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")
    parser.add_argument("--json", action="store_true", help="print the results as JSON")
    parser.set_defaults(handler=run_evaluate)


def families(text: str) -> tuple[str, ...]:
    """The family names of ``--families`` (comma-separated); an unknown one is a ``InputError``."""
    names = tuple(name.strip() for name in text.split(",") if name.strip())
    unknown = [name for name in names if name not in FAMILY_NAMES]
    if not names or unknown:
        raise InputError(f"unknown family {', '.join(unknown) or '(none)'}: choose from {', '.join(FAMILY_NAMES)}")
    return names


def run_evaluate(args: argparse.Namespace) -> int:
    check_seed_range(args.seed + args.start, args.episodes)
    try:
        results = evaluate_expert(
            families(args.families),
            episodes=args.episodes,
            seed=args.seed,
            start=args.start,
            workers=args.workers,
            time_limit=args.time_limit,
            failures_dir=Path(args.failures_dir) if args.failures_dir else None,
            progress=not args.no_progress,
        )
    except EvaluationInterrupted as interrupted:  # keep what finished: print its figures, then exit 130
        if interrupted.results:
            _print_evaluation(interrupted.results, args.json)
        finished = sum(r.episodes for r in interrupted.results)
        say(f"interrupted after {finished} finished episode(s); the figures above are theirs")
        return INTERRUPTED
    _print_evaluation(results, args.json)
    return 0 if all(r.success_rate >= SUCCESS_GOAL for r in results) else 1


def _print_evaluation(results: list[Any], as_json: bool) -> None:
    if as_json:
        print(json.dumps([r.to_dict() for r in results], indent=2))
        return
    echo(results_table(results))
    for result in results:
        for failure in result.failures:
            echo(f"failed: {failure['family']} seed {failure['seed']}: {failure['outcome']} ({failure['replay']})")
