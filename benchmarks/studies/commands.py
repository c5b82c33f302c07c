"""``python -m benchmarks learned|learning-checks|projection``: the studies' options.

``learned`` measures trained run folders on held-out seeds against the MILP expert;
``learning-checks`` trains small BC and MaskablePPO runs in this process and says
whether they learn (:mod:`benchmarks.studies.learning`); ``projection`` runs the expert
through the candidate phases' projection (:mod:`benchmarks.studies.projection`). Exit
statuses: 0 measured, 2 bad input (an unknown family, a folder that is not a run folder,
a DIR that holds a run already).
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from training import load_policy
from training.cli.arguments import positive_float, positive_int, whole_number
from training.cli.episodes import families
from training.cli.options import Command
from training.cli.seeds import seed
from training.cli.text import echo
from training.learners.options import HELDOUT_SEED_BASE, BCConfig, check_family
from training.resolve import run_image_options

PROJECTION_COMMAND = Command(
    name="projection",
    help="the expert recorded in candidate phases (inexpressible moves projected) against its own episodes",
    description="Run the MILP expert through FetchCarryPushPhases-v0 as `generate --interface phases` records "
    "it (a move no candidate expresses replaced by the nearest allowed move, then the expert plans again) and "
    "on its own, on the same seeds, and print both success rates, the projected moves per episode and the "
    "extra travel cost of the projection (JSON).",
)


def register(bench: argparse._SubParsersAction) -> None:
    """Add ``learned``, ``learning-checks`` and ``projection`` to the parser of ``python -m benchmarks``."""
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
    learned.set_defaults(handler=run_learned)
    _register_learning_checks(bench)
    _register_projection(bench)


def _register_learning_checks(bench: argparse._SubParsersAction) -> None:
    epochs = BCConfig().epochs
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
    bc.add_argument("--epochs", type=positive_int, default=epochs, metavar="N", help=f"epochs (default {epochs})")
    bc.add_argument("--out", metavar="DIR", help="write a run folder per encoder into DIR")
    bc.add_argument("--also", nargs="*", default=[], metavar="NAME", help="other families to evaluate on (multi-3)")
    bc.set_defaults(handler=run_check_bc)
    ppo = checks.add_parser("ppo", help="MaskablePPO with the learning reward")
    ppo.add_argument("--family", default="basic", metavar="NAME", help="scenario family (default basic)")
    ppo.add_argument("--steps", type=positive_int, default=20_000, metavar="N", help="env steps (default 20000)")
    ppo.add_argument("--eval-episodes", type=positive_int, default=50, metavar="N", help="held-out seeds (default 50)")
    ppo.add_argument("--seed", type=seed, default=0, metavar="N", help="training seed (default 0)")
    ppo.add_argument("--out", metavar="DIR", help="write ppo.zip and metrics.csv into DIR")
    ppo.set_defaults(handler=run_check_ppo)


def _check_families(*names: str) -> None:
    for name in names:
        check_family(name)  # InputError for an unknown name, before any work


def run_learned(args: argparse.Namespace) -> int:
    import torch

    from training.learners.heldout import evaluate, expert_costs, summarise
    from training.learners.runs import read_saved

    _check_families(args.family)
    torch.set_num_threads(1)  # one decision at a time: a second thread made it about 60x slower here
    policies = {run: load_policy(run) for run in args.runs}  # RunFolderError: bad input
    seeds = range(args.first_seed, args.first_seed + args.episodes)
    expert = expert_costs(args.family, seeds)
    echo(f"{args.family}: {args.episodes} held-out seeds from {args.first_seed}; the expert solves {len(expert)}")
    for run, policy in policies.items():
        images = run_image_options(read_saved(run))  # an image network's env: its own observation mode
        echo(summarise(evaluate(policy, args.family, seeds, **images), expert).line(run))
    return 0


def run_check_bc(args: argparse.Namespace) -> int:
    from benchmarks.studies.learning import check_bc

    _check_families(args.family, *args.also)
    out = Path(args.out) if args.out else None
    check_bc(args.family, args.episodes, args.eval_episodes, args.encoders, args.epochs, out, args.also, echo)
    return 0


def run_check_ppo(args: argparse.Namespace) -> int:
    from benchmarks.studies.learning import check_ppo

    _check_families(args.family)
    check_ppo(args.family, args.steps, args.eval_episodes, args.seed, Path(args.out) if args.out else None, echo)
    return 0


def _register_projection(bench: argparse._SubParsersAction) -> None:
    from training.policies.phase_expert import NEAREST_RULES

    parser = PROJECTION_COMMAND.add(bench, run_projection)
    parser.add_argument("--family", required=True, metavar="F", help="scenario family, e.g. basic or push")
    parser.add_argument("--episodes", type=positive_int, default=100, metavar="N", help="episodes (default 100)")
    parser.add_argument("--seed", type=seed, default=0, metavar="S", help="first seed (default 0)")
    parser.add_argument(
        "--rule", choices=NEAREST_RULES, default="end", help="which allowed move stands in (default end)"
    )
    parser.add_argument(
        "--time-limit", type=positive_float, default=10.0, metavar="S", help="seconds per planning call (default 10)"
    )


def run_projection(args: argparse.Namespace) -> int:
    """Print the projection's figures as one JSON object."""
    from benchmarks.studies.projection import check_projection, summarise_projection

    families(args.family)  # an unknown family is bad input
    seeds = range(args.seed, args.seed + args.episodes)
    rows = check_projection(args.family, seeds, time_limit=args.time_limit, rule=args.rule)
    echo(json.dumps({"family": args.family, "rule": args.rule, **summarise_projection(rows)}, indent=2))
    return 0
