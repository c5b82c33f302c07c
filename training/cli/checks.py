"""The learning checks: ``fetchcarry bench learned`` and ``fetchcarry bench learning-checks bc|ppo``.

``bench learned`` measures trained run folders on held-out seeds against the MILP expert;
``bench learning-checks`` trains small BC and MaskablePPO runs in this process and says
whether they learn. Exit statuses: 0 measured, 2 bad input (an unknown family, a folder
that is not a run folder, a DIR that holds a run already).
"""

from __future__ import annotations

import argparse
from pathlib import Path

from training import load_policy
from training.cli.arguments import positive_int, whole_number
from training.cli.seeds import seed
from training.cli.text import echo
from training.learners.options import HELDOUT_SEED_BASE, BCConfig, check_family
from training.resolve import run_image_options


def register(commands: argparse._SubParsersAction, bench: argparse._SubParsersAction) -> None:
    """Add ``bench learned`` and ``bench learning-checks`` to the ``fetchcarry`` parser."""
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
    _register_learning_checks(bench)


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


def run_bench_learned(args: argparse.Namespace) -> int:
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
    from training.evaluation.checks import check_bc

    _check_families(args.family, *args.also)
    out = Path(args.out) if args.out else None
    check_bc(args.family, args.episodes, args.eval_episodes, args.encoders, args.epochs, out, args.also, echo)
    return 0


def run_check_ppo(args: argparse.Namespace) -> int:
    from training.evaluation.checks import check_ppo

    _check_families(args.family)
    check_ppo(args.family, args.steps, args.eval_episodes, args.seed, Path(args.out) if args.out else None, echo)
    return 0
