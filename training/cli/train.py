"""The training commands: ``fetchcarry train bc|dagger|ppo``, ``fetchcarry bench learned|learning-checks``.

Each writes a run folder (``config.json``, ``metrics.csv``, ``checkpoint.pt``,
``model.pt``; see :mod:`training.learners.runs`) that ``fetchcarry benchmark`` and
``fetchcarry rollout --policy RUN_DIR`` take, and ``training.load_policy(path)`` loads.

Exit statuses: 0 trained (also when the run folder already held the complete run);
2 bad input; 130 interrupted (the last checkpoint is kept: the same command with
``--resume`` finishes the run).
"""

from __future__ import annotations

import argparse
import sys
from typing import Any

from fetchcarry_env.errors import UsageError
from training.cli.arguments import positive_float, positive_int, whole_number
from training.cli.exits import INTERRUPTED, ignore_unraisable, say
from training.cli.text import echo

RUN_EPILOG = (
    "The run folder holds config.json (the kind, the interface and every option), metrics.csv, checkpoint.pt and, "
    "once finished, model.pt. Exit status: 0 trained, 2 bad input, 130 interrupted (the last checkpoint is kept: "
    "run the same command with --resume to finish)."
)


def register(commands: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``train`` (``bc``, ``dagger``, ``ppo``, ``ensemble``) to the ``fetchcarry`` parser."""
    from training.learners.options import BCConfig

    defaults = BCConfig()
    parser = commands.add_parser(
        "train",
        help="train a learned baseline (bc, dagger, ppo; or an ensemble of runs) into a run folder",
        description="Train a learned policy on the candidate-phase interface (FetchCarryPushPhases-v0) into a "
        "run folder. Deterministic on CPU for one --seed.",
    )
    kinds = parser.add_subparsers(dest="kind", metavar="KIND", required=True)

    bc = kinds.add_parser(
        "bc",
        help="behaviour cloning on a Minari dataset recorded with --interface phases",
        description="Behaviour cloning: a network scores every candidate phase from the observation, trained "
        "with cross-entropy on the expert's choices among the allowed candidates of a dataset made by "
        "'fetchcarry generate ... --interface phases'.",
        epilog=RUN_EPILOG,
    )
    bc.add_argument("--dataset", required=True, metavar="ID", help="Minari dataset id (made with --interface phases)")
    bc.add_argument(
        "--episodes", type=positive_int, metavar="N", help="train on the dataset's first N episodes (default: all)"
    )
    _network_arguments(bc, defaults)
    _run_arguments(bc)
    bc.set_defaults(handler=run_train_bc)

    from training.learners.options import DaggerOptions

    dagger_defaults = DaggerOptions()
    dagger = kinds.add_parser(
        "dagger",
        help="DAgger: the learner acts, the MILP expert labels the states it visits",
        description="DAgger: BC on expert demonstrations, then iterations in which the learner acts on new seeds "
        "of the family, the MILP expert labels every state it visits (mapped to candidates; an action no "
        "candidate expresses gives no label) and the network is retrained on the aggregate. Labelling runs on "
        "the same worker pool (or Ray) as fetchcarry generate. metrics.csv: one row per iteration with the "
        "expert labels so far and the success on held-out seeds.",
        epilog=RUN_EPILOG,
    )
    dagger.add_argument("--family", required=True, metavar="NAME", help="scenario family (basic, push, ...)")
    dagger.add_argument(
        "--demonstrations",
        type=positive_int,
        default=dagger_defaults.demonstrations,
        metavar="N",
        help=f"expert episodes before the first iteration (default {dagger_defaults.demonstrations})",
    )
    dagger.add_argument(
        "--iterations",
        type=positive_int,
        default=dagger_defaults.iterations,
        metavar="N",
        help=f"DAgger iterations (default {dagger_defaults.iterations})",
    )
    dagger.add_argument(
        "--episodes-per-iteration",
        type=positive_int,
        default=dagger_defaults.episodes_per_iteration,
        metavar="N",
        help=f"learner episodes per iteration (default {dagger_defaults.episodes_per_iteration})",
    )
    dagger.add_argument(
        "--eval-episodes",
        type=positive_int,
        default=dagger_defaults.eval_episodes,
        metavar="N",
        help=f"held-out episodes per iteration (default {dagger_defaults.eval_episodes})",
    )
    dagger.add_argument(
        "--time-limit",
        type=positive_float,
        default=dagger_defaults.time_limit,
        metavar="S",
        help=f"seconds per planning call of the expert (default {dagger_defaults.time_limit:g})",
    )
    dagger.add_argument(
        "--nearest-moves",
        action="store_true",
        help="label an expert move no candidate expresses with the allowed move nearest it (default: no label)",
    )
    dagger.add_argument(
        "--learner-families",
        type=_family_list,
        default=(),
        metavar="NAME[,NAME...]",
        help="families the learner episodes draw from, in turn (for example push,multi-2: where learners fail "
        "most); iteration 0 and the held-out success stay on --family (default: --family)",
    )
    dagger.add_argument(
        "--dataset",
        metavar="ID",
        help="iteration 0 trains on the first --demonstrations episodes of this phases dataset instead of running "
        "the expert again (default: new expert episodes)",
    )
    dagger.add_argument("--workers", type=positive_int, default=1, metavar="W", help="labelling workers (default 1)")
    dagger.add_argument(
        "--backend", choices=("process", "ray"), default="process", help="a local process pool (default) or Ray"
    )
    _network_arguments(dagger, defaults, epochs=dagger_defaults.epochs)
    _run_arguments(dagger)
    dagger.set_defaults(handler=run_train_dagger)

    from training.learners.options import PPOOptions

    ppo_defaults = PPOOptions()
    ppo = kinds.add_parser(
        "ppo",
        help="MaskablePPO (sb3-contrib) on the candidate phases with the learning reward",
        description="sb3-contrib's MaskablePPO on FetchCarryPushPhases-v0 with the learning reward (potential-"
        "shaped progress, refusals cost more than moving). The actor is the BC network of --encoder, so --init "
        "RUN_DIR (a bc or dagger run of the same encoder) starts it from those weights. metrics.csv: one row per "
        "rollout with env steps, wall-clock seconds, and the training episodes' success, return and the paper's "
        "travel cost.",
        epilog=RUN_EPILOG,
    )
    ppo.add_argument("--family", required=True, metavar="NAME", help="scenario family (basic, push, ...)")
    ppo.add_argument(
        "--steps",
        type=positive_int,
        default=ppo_defaults.steps,
        metavar="N",
        help=f"env steps in total (default {ppo_defaults.steps})",
    )
    ppo.add_argument("--init", metavar="RUN_DIR", help="a bc or dagger run folder whose network starts the actor")
    ppo.add_argument(
        "--n-steps",
        type=positive_int,
        default=ppo_defaults.n_steps,
        metavar="N",
        help=f"env steps per rollout (default {ppo_defaults.n_steps})",
    )
    ppo.add_argument(
        "--learning-rate",
        type=positive_float,
        default=ppo_defaults.learning_rate,
        metavar="LR",
        help=f"Adam step size (default {ppo_defaults.learning_rate:g})",
    )
    ppo.add_argument(
        "--checkpoint-every",
        type=positive_int,
        default=ppo_defaults.checkpoint_every,
        metavar="N",
        help=f"env steps between checkpoints (default {ppo_defaults.checkpoint_every})",
    )
    ppo.add_argument(
        "--encoder",
        choices=("mlp", "set"),
        default=defaults.encoder,
        help=f"the actor's network (default {defaults.encoder}; with --init, the init run's)",
    )
    ppo.add_argument(
        "--hidden",
        type=positive_int,
        default=defaults.hidden,
        metavar="N",
        help=f"units per hidden layer / token width (default {defaults.hidden})",
    )
    _run_arguments(ppo)
    ppo.set_defaults(handler=run_train_ppo)

    ensemble = kinds.add_parser(
        "ensemble",
        help="combine trained run folders into one policy (no further training)",
        description="Combine two or more finished run folders (bc, dagger or ppo, the same observation capacity) "
        "into one run folder whose policy acts on the mean of their log-probabilities: a candidate ranks first "
        "when the members agree on it. The members' weights are copied, so the folder stands alone. For example "
        "the three training seeds of dagger-aimed of a reproduction.",
        epilog="Exit status: 0 written, 2 bad input (a member that is not a finished run folder, members that "
        "score other candidates, an OUT that holds a run).",
    )
    ensemble.add_argument("--members", nargs="+", required=True, metavar="RUN_DIR", help="finished run folders")
    ensemble.add_argument(
        "--no-avoid-returns",
        dest="avoid_returns",
        action="store_false",
        help="act without the episode memory that skips moves known to lead back to a state met before",
    )
    ensemble.add_argument("--out", required=True, metavar="RUN_DIR", help="the run folder to write")
    ensemble.set_defaults(handler=run_train_ensemble)

    from training.learners.options import HELDOUT_SEED_BASE

    learned = bench.add_parser(
        "learned",
        help="held-out success and cost ratio of trained run folders against the expert",
        description="Run each run folder's policy (deterministic, masked) for one episode per held-out seed of "
        "a family in FetchCarryPushPhases-v0, and the MILP expert on the same seeds; print success with a 95 % "
        "Wilson interval, the cost ratio to the expert (successful episodes), phases, refusals and time per "
        "decision.",
    )
    learned.add_argument("runs", nargs="+", metavar="RUN_DIR", help="run folders of fetchcarry train")
    learned.add_argument("--family", required=True, metavar="NAME", help="scenario family (basic, push, ...)")
    learned.add_argument("--episodes", type=positive_int, default=100, metavar="N", help="held-out seeds (default 100)")
    learned.add_argument(
        "--first-seed",
        type=whole_number,
        default=HELDOUT_SEED_BASE,
        metavar="N",
        help=f"the first held-out seed (default {HELDOUT_SEED_BASE}: never trained on)",
    )
    learned.set_defaults(handler=run_bench_learned)
    _register_learning_checks(bench, defaults)


def _register_learning_checks(bench: argparse._SubParsersAction, defaults: Any) -> None:
    parser = bench.add_parser(
        "learning-checks",
        help="quick in-process checks: does a small BC or MaskablePPO learn on the candidate phases?",
        description="In-process learning checks on FetchCarryPushPhases-v0, evaluated on held-out seeds (from "
        "100000) next to the masked random policy and the MILP expert: bc records the expert's episodes, trains "
        "BC with each encoder and adds the greedy baseline; ppo trains MaskablePPO with the learning reward and "
        "evaluates it five times on the way. Figures print as they are measured.",
    )
    checks = parser.add_subparsers(dest="check", metavar="CHECK", required=True)
    bc = checks.add_parser("bc", help="behaviour cloning from expert episodes recorded in this process")
    bc.add_argument("--family", default="basic", metavar="NAME", help="scenario family (default basic)")
    bc.add_argument(
        "--episodes", type=positive_int, default=300, metavar="N", help="expert episodes to learn from (default 300)"
    )
    bc.add_argument("--eval-episodes", type=positive_int, default=100, metavar="N", help="held-out seeds (default 100)")
    bc.add_argument("--encoders", nargs="+", choices=("mlp", "set"), default=["mlp", "set"], help="(default both)")
    bc.add_argument(
        "--epochs", type=positive_int, default=defaults.epochs, metavar="N", help=f"epochs (default {defaults.epochs})"
    )
    bc.add_argument("--out", metavar="DIR", help="write a run folder per encoder into DIR")
    bc.add_argument("--also", nargs="*", default=[], metavar="NAME", help="other families to evaluate on (multi-3)")
    bc.set_defaults(handler=run_check_bc)
    ppo = checks.add_parser("ppo", help="MaskablePPO with the learning reward")
    ppo.add_argument("--family", default="basic", metavar="NAME", help="scenario family (default basic)")
    ppo.add_argument("--steps", type=positive_int, default=20_000, metavar="N", help="env steps (default 20000)")
    ppo.add_argument("--eval-episodes", type=positive_int, default=50, metavar="N", help="held-out seeds (default 50)")
    ppo.add_argument("--seed", type=whole_number, default=0, metavar="N", help="training seed (default 0)")
    ppo.add_argument("--out", metavar="DIR", help="write ppo.zip and metrics.csv into DIR")
    ppo.set_defaults(handler=run_check_ppo)


def _network_arguments(parser: argparse.ArgumentParser, defaults: Any, epochs: int | None = None) -> None:
    parser.add_argument(
        "--encoder",
        choices=("mlp", "set"),
        default=defaults.encoder,
        help=f"flat MLP or object-centric set encoder (default {defaults.encoder})",
    )
    parser.add_argument(
        "--hidden",
        type=positive_int,
        default=defaults.hidden,
        metavar="N",
        help=f"units per hidden layer / token width (default {defaults.hidden})",
    )
    epochs = defaults.epochs if epochs is None else epochs
    parser.add_argument(
        "--epochs",
        type=positive_int,
        default=epochs,
        metavar="N",
        help=f"epochs (per iteration for dagger; default {epochs})",
    )
    parser.add_argument(
        "--batch-size",
        type=positive_int,
        default=defaults.batch_size,
        metavar="N",
        help=f"minibatch size (default {defaults.batch_size})",
    )
    parser.add_argument(
        "--learning-rate",
        type=positive_float,
        default=defaults.learning_rate,
        metavar="LR",
        help=f"Adam step size (default {defaults.learning_rate:g})",
    )


def _run_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--seed", type=whole_number, default=0, metavar="N", help="training seed (default 0)")
    parser.add_argument("--out", required=True, metavar="RUN_DIR", help="the run folder to write")
    parser.add_argument("--resume", action="store_true", help="finish the interrupted run in RUN_DIR")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def _network_config(args: argparse.Namespace) -> Any:
    from training.learners.options import BCConfig

    try:
        return BCConfig(encoder=args.encoder, hidden=args.hidden, epochs=args.epochs, batch_size=args.batch_size,
                        learning_rate=args.learning_rate, seed=args.seed)  # fmt: skip
    except ValueError as error:
        raise UsageError(str(error)) from None


def _guarded(train: Any, args: argparse.Namespace) -> int:
    """Run ``train()``; library ``ValueError`` is bad input, Ctrl-C keeps the checkpoint."""
    try:
        summary = train()
    except KeyboardInterrupt:
        sys.unraisablehook = ignore_unraisable
        say(f"interrupted: the last checkpoint in {args.out} is kept; add --resume to the same command to finish")
        return INTERRUPTED
    except ValueError as error:
        raise UsageError(str(error)) from None
    echo(summary)
    return 0


def run_train_bc(args: argparse.Namespace) -> int:
    from training.learners.imitation import train_bc_run
    from training.learners.runs import read_metrics

    config = _network_config(args)

    def train() -> str:
        train_bc_run(args.dataset, config, args.out, resume=args.resume, progress=not args.no_progress,
                     episodes=args.episodes)  # fmt: skip
        last = read_metrics(args.out)[-1]
        return (f"bc ({config.encoder}) on {args.dataset}: {int(last['epoch'])} epochs, loss {last['loss']:.3f}, "
                f"accuracy {last['accuracy']:.1%}\nrun folder {args.out}")  # fmt: skip

    return _guarded(train, args)


def run_train_ensemble(args: argparse.Namespace) -> int:
    from training.learners.ensemble import make_ensemble

    try:
        make_ensemble(args.members, args.out, avoid_returns=args.avoid_returns)
    except ValueError as error:
        raise UsageError(str(error)) from None
    echo(f"ensemble of {len(args.members)} runs\nrun folder {args.out}")
    return 0


def _family_list(text: str) -> tuple[str, ...]:
    """``push,multi-2`` -> ``("push", "multi-2")``, each a known family (argparse's type)."""
    from fetchcarry_env.families import FAMILY_NAMES

    names = tuple(name.strip() for name in text.split(",") if name.strip())
    unknown = [name for name in names if name not in FAMILY_NAMES]
    if not names or unknown:
        raise argparse.ArgumentTypeError(
            f"expected family names separated by commas ({', '.join(FAMILY_NAMES)}), got {text!r}"
        )
    return names


def run_train_dagger(args: argparse.Namespace) -> int:
    from training.data.sources import EpisodeSource
    from training.learners.dagger import DaggerOptions, train_dagger

    EpisodeSource(family=args.family)  # checks the family's name (UsageError)
    config = _network_config(args)
    options = DaggerOptions(
        demonstrations=args.demonstrations,
        iterations=args.iterations,
        episodes_per_iteration=args.episodes_per_iteration,
        eval_episodes=args.eval_episodes,
        time_limit=args.time_limit,
        epochs=args.epochs,
        nearest_moves=args.nearest_moves,
        learner_families=args.learner_families,
        dataset=args.dataset,
    )

    def train() -> str:
        rows = train_dagger(args.family, options, config, args.out, workers=args.workers, backend=args.backend,
                            resume=args.resume, progress=not args.no_progress)  # fmt: skip
        last = rows[-1]
        return (f"dagger ({config.encoder}) on {args.family}: {int(last['iteration'])} iterations, "
                f"{int(last['expert_labels'])} expert labels, held-out success {last['heldout_success']:.1%}\n"
                f"run folder {args.out}")  # fmt: skip

    return _guarded(train, args)


def run_train_ppo(args: argparse.Namespace) -> int:
    from training.data.sources import EpisodeSource
    from training.learners.ppo import PPOOptions, train_ppo

    EpisodeSource(family=args.family)  # checks the family's name (UsageError)
    options = PPOOptions(
        steps=args.steps,
        n_steps=args.n_steps,
        learning_rate=args.learning_rate,
        checkpoint_every=args.checkpoint_every,
        encoder=args.encoder,
        hidden=args.hidden,
        seed=args.seed,
        init=args.init,
    )

    def train() -> str:
        rows = train_ppo(args.family, options, args.out, resume=args.resume, progress=not args.no_progress)
        last = rows[-1] if rows else {}
        return (f"ppo ({options.encoder}) on {args.family}: {int(last.get('steps', 0))} env steps, recent training "
                f"success {last.get('success', float('nan')):.1%}\nrun folder {args.out}")  # fmt: skip

    return _guarded(train, args)


def run_bench_learned(args: argparse.Namespace) -> int:
    import torch

    from training import load_policy
    from training.data.sources import EpisodeSource
    from training.learners.heldout import evaluate, expert_costs, summarise

    EpisodeSource(family=args.family)  # checks the family's name (UsageError)
    torch.set_num_threads(1)  # one decision at a time: a second thread made it about 60x slower here
    try:
        policies = {run: load_policy(run) for run in args.runs}
    except ValueError as error:
        raise UsageError(str(error)) from None
    seeds = range(args.first_seed, args.first_seed + args.episodes)
    expert = expert_costs(args.family, seeds)
    echo(f"{args.family}: {args.episodes} held-out seeds from {args.first_seed}; the expert solves {len(expert)}")
    for run, policy in policies.items():
        echo(summarise(evaluate(policy, args.family, seeds), expert).line(run))
    return 0


def _check_families(*names: str) -> None:
    from training.data.sources import EpisodeSource

    for name in names:
        EpisodeSource(family=name)  # checks the family's name (UsageError)


def run_check_bc(args: argparse.Namespace) -> int:
    from pathlib import Path

    from training.evaluation.checks import check_bc

    _check_families(args.family, *args.also)
    out = Path(args.out) if args.out else None
    try:
        check_bc(args.family, args.episodes, args.eval_episodes, args.encoders, args.epochs, out, args.also, echo)
    except ValueError as error:  # a run folder already in DIR
        raise UsageError(str(error)) from None
    return 0


def run_check_ppo(args: argparse.Namespace) -> int:
    from pathlib import Path

    from training.evaluation.checks import check_ppo

    _check_families(args.family)
    check_ppo(args.family, args.steps, args.eval_episodes, args.seed, Path(args.out) if args.out else None, echo)
    return 0
