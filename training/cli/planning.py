"""The planner's commands: ``fetchcarry plan`` and ``fetchcarry validate``.

Exit statuses: ``plan`` 0 when a plan was found and 1 when none (infeasible, time
limit); ``validate`` 0 for a valid plan (or, given no plan, a valid scenario) and 1 for
an invalid one; 2 for bad input
(raised here as ``InputError``, ``ScenarioError`` or ``PlanFormatError`` and turned
into one short message by :func:`training.cli.main`).
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path
from typing import Any

from expert.plans import Phase, Plan, phase_rows, plan_length
from expert.validate import env_refusals, validate_plan
from fetchcarry_env.errors import InputError
from fetchcarry_env.scenario import Scenario, ScenarioError
from training.cli.arguments import non_negative_int, positive_float, positive_int
from training.cli.commands import summary
from training.cli.files import (
    check_plot_format,
    check_readable,
    check_writable,
    file_format,
    load_plan,
    load_scenario,
)
from training.cli.options import Command
from training.cli.text import echo
from training.errors import BenchmarkError
from training.guidance import rollout_plan

DEFAULT_TIME_LIMIT = 10.0  # seconds for the whole planning call
MAX_SUMMARY_PHASES = 30  # phases listed in the one-screen summary
MAX_SUMMARY_VIOLATIONS = 5  # validator messages repeated in the plan summary

PLAN_FORMAT = "fetchcarry-plan/1"
INTERRUPTED_STATUS = "userinterrupt"  # SCIP's status of a solve stopped by Ctrl-C
SCENARIO_FORMAT = "fetchcarry-scenario/1"

PLAN_COMMAND = Command(
    name="plan",
    help=summary("plan"),
    description="Plan SCENARIO (a fetchcarry-scenario/1 file) with the paper's MILP on SCIP, print a "
    "one-screen summary (status, objective, the phases, timings) and, with -o PLAN, write the plan as "
    "fetchcarry-plan/1 JSON; without -o no file is written. The plan is written whatever the outcome: "
    "a plan without phases records the status (infeasible, time_limit) and the timings. The command also "
    "checks the plan with the validator and warns on stderr if it breaks the rules of docs/plan-format.md.",
    epilog="Exit status: 0 a plan was found, 1 no plan (infeasible or time limit), 2 bad input.",
)
VALIDATE_COMMAND = Command(
    name="validate",
    help=summary("validate"),
    description="Without PLAN: check SCENARIO alone against the rules of docs/scenario-format.md (its "
    "fields, unique ids, rectangles, the robot's start, objects and goals on tables, no overlaps, "
    "numbers and counts), without planning, and list every violation; --plot draws it from above. "
    "With PLAN (fetchcarry-plan/1): check the plan for SCENARIO against the rules of docs/plan-format.md "
    "(area and clearance of the base, holding, objects that stay, reach and arm line, pushes, "
    "the goal at the end) and docs/design.md's execution rules (a place delivers; a push needs "
    "a forward or lateral stroke, the contact within reach and room for the hand). Every violation is "
    "listed, one line each, naming the rule, the phase and the ids; --plot draws the plan.",
    epilog="Exit status: 0 valid, 1 invalid (without PLAN: the scenario breaks the rules of "
    "docs/scenario-format.md), 2 bad input (a missing file, broken JSON, a file that is not "
    "fetchcarry-scenario/1; with PLAN, a scenario that breaks the rules, a plan file that is not "
    "fetchcarry-plan/1).",
)


def register(commands: argparse._SubParsersAction) -> None:
    """Add ``plan`` and ``validate`` to the ``fetchcarry`` parser."""
    _add_plan_options(PLAN_COMMAND.add(commands, run_plan))
    _add_validate_options(VALIDATE_COMMAND.add(commands, run_validate))


# ---------------------------------------------------------------------- plan
def _add_plan_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", metavar="SCENARIO", help="scenario file (JSON, fetchcarry-scenario/1)")
    parser.add_argument(
        "-o",
        "--output",
        metavar="PLAN",
        help="write the plan JSON to this file (default: no file is written, the summary shows the phases; "
        "a command run from a repository or a home folder should leave no file there unasked)",
    )
    parser.add_argument(
        "--time-limit",
        type=positive_float,
        default=DEFAULT_TIME_LIMIT,
        metavar="S",
        help=f"seconds for the whole planning call, model building included (default {DEFAULT_TIME_LIMIT:g})",
    )
    parser.add_argument(
        "--max-phases",
        type=positive_int,
        default=None,
        metavar="N",
        help="the largest number of phases to try (default: the planner's own bound)",
    )
    parser.add_argument(
        "--extra-phases",
        type=non_negative_int,
        default=None,
        metavar="K",
        help="optimise only over plans of at most K phases beyond the fewest that admit one; 0 is the paper's "
        "rule (optimal among the plans with the fewest phases). Default: the least task cost over every "
        "number of phases (the env's return and the benchmark's cost)",
    )
    parser.add_argument("--plot", metavar="PNG", help="also draw the plan from above into this image file")
    parser.add_argument(
        "--export-model",
        metavar="DIR",
        help="write the MILP of each phase count solved into this folder (made if missing): "
        "<scenario>_N<phases>.mps and a .json of what every variable means, SCIP's status and the optimum "
        "(for learned MILP solving; any MPS reader such as HiGHS finds the same optimum)",
    )
    parser.add_argument(
        "--guide",
        metavar="GUIDE",
        help="a plan to guide the search: a plan file (fetchcarry-plan/1), or a policy whose episode on SCENARIO "
        "becomes the plan (a name such as greedy or expert-phases, a run folder of fetchcarry train, or "
        "package.module:factory, your own factory called with the env that returns a policy, found from the "
        "working folder first: naming it imports and runs your code, so trust it as you would a script you run); "
        "SCIP's warm start where it fits a model (as it is, or with its moves dropped), the optimum and its proof "
        "unchanged",
    )
    parser.add_argument(
        "--guide-branching",
        action="store_true",
        help="with --guide: also branch first on the guide's choices (a hint; the proof is unchanged)",
    )
    parser.add_argument("--json", action="store_true", help="print the summary as one JSON object instead of a table")


def run_plan(args: argparse.Namespace) -> int:
    """``fetchcarry plan``: 0 a plan was found, 1 none."""
    scenario_path = Path(args.scenario)
    scenario = load_scenario(scenario_path)
    output = Path(args.output) if args.output else None
    if output is not None:
        check_writable(output, "plan output")
    plot_path = Path(args.plot) if args.plot else None
    if plot_path is not None:
        check_writable(plot_path, "plot")
        check_plot_format(plot_path)

    export_dir = _export_dir(args.export_model)
    if args.guide_branching and args.guide is None:
        raise InputError("--guide-branching needs --guide GUIDE")
    guide = None if args.guide is None else load_guide(args.guide, scenario)

    from expert.planner import plan as run_planner  # imported here: pyscipopt costs about 0.15 s

    result = run_planner(
        scenario,
        time_limit=args.time_limit,
        max_phases=args.max_phases,
        extra_phases=args.extra_phases,
        export_models=export_dir,
        guide=guide,
        guide_branching=args.guide_branching,
    )
    if result.status == INTERRUPTED_STATUS:  # a solve cut short by Ctrl-C is never written as a plan
        raise KeyboardInterrupt
    if output is not None:
        result.save(output)
    violations = validate_plan(scenario, result) if result.found else []
    if plot_path is not None:
        from expert.plot import plot_plan  # matplotlib only when a picture is asked for

        plot_plan(scenario, result, plot_path)

    if args.json:
        print(json.dumps(_plan_summary_json(scenario_path, result, output, plot_path, violations), indent=2))
    else:
        text = _plan_summary_text(scenario_path, result, output, plot_path, args.time_limit)
        guide_line = _guide_text(result, guide)
        echo(text if guide_line is None else f"{text}\nguide      {guide_line}")
    if violations:
        shown = "\n".join(f"  - {v}" for v in violations[:MAX_SUMMARY_VIOLATIONS])
        more = len(violations) - MAX_SUMMARY_VIOLATIONS
        tail = f"\n  ... and {more} more (fetchcarry validate lists them all)" if more > 0 else ""
        echo(f"fetchcarry: warning: the plan breaks the rules of docs/plan-format.md:\n{shown}{tail}", file=sys.stderr)
    return 0 if result.found else 1


def load_guide(text: str, scenario: Scenario) -> Plan:
    """The guide ``--guide`` names: a plan file as it is, else the episode of the policy it names on ``scenario``."""
    path = Path(text)
    if path.is_file():
        return load_plan(path)
    try:
        return rollout_plan(text, scenario)
    except BenchmarkError as error:
        raise InputError(f"--guide {text}: not a plan file, and {error}") from None


def _guide_text(plan: Plan, guide: Plan | None) -> str | None:
    """One line on the guide: where it came from, its phases, whether it mapped and was taken as a warm start."""
    if guide is None:
        return None
    source = guide.stats.get("policy")
    origin = (
        f"episode of {source} ({'delivered' if guide.stats.get('delivered') else 'not delivered'}, "
        f"{guide.stats.get('rollout_s', 0.0):.2f} s)"
        if source
        else f"plan file ({guide.status})"
    )
    solves = [s for s in plan.stats.get("solves", []) if isinstance(s, dict)]
    taken = "yes" if any(s.get("guide_warm_start") for s in solves) else "no (it fits no model, or is not a plan of it)"
    mapped = plan.stats.get("guide", "-")
    return f"{origin}, {len(guide.phases)} phases: {mapped}; SCIP took it as a warm start: {taken}"


def _export_dir(path: str | None) -> Path | None:
    """The folder for ``--export-model`` (made if missing), or None; a path that is not a folder is bad input."""
    if path is None:
        return None
    folder = Path(path)
    if folder.exists() and not folder.is_dir():
        raise InputError(f"--export-model {folder}: not a folder")
    try:
        folder.mkdir(parents=True, exist_ok=True)
    except OSError as error:
        raise InputError(f"--export-model {folder}: cannot make the folder ({error.strerror})") from None
    return folder


def _plan_summary_text(
    scenario_path: Path, plan: Plan, output: Path | None, plot_path: Path | None, time_limit: float
) -> str:
    objective = "-" if plan.objective is None else f"{plan.objective:.3f}"
    lines = [
        f"scenario   {plan.scenario} ({scenario_path})",
        f"status     {plan.status}    objective {objective}",
    ]
    if not plan.found:
        lines.append(f"why        {no_plan_reason(plan, time_limit)}")
    elif plan.stats.get("optimality"):
        gap = plan.stats.get("gap")
        proven = ""
        if plan.status == "feasible":
            no_gap = " (no proven gap: no bound covers its phases)"
            proven = f" (proven gap {gap:.1%})" if isinstance(gap, float) else no_gap
        lines.append(f"meaning    {plan.stats['optimality']}{proven}")
    lines += [
        f"phases     {plan_length(len(plan.phases)) if plan.phases else 0}" + _phases_tried(plan),
        f"timings    {_timings(plan)}",
    ]
    if plan.phases:
        lines += ["", _phase_table(plan)]
    lines += ["", f"plan written to {output}" if output is not None else "plan not written (-o PLAN writes it)"]
    exported = [s["exported"] for s in plan.stats.get("solves", []) if isinstance(s, dict) and "exported" in s]
    if exported:
        lines.append(f"models written: {', '.join(exported)} (each with a .json of its variables and optimum)")
    if plot_path is not None:
        lines.append(f"plot written to {plot_path}")
    return "\n".join(lines)


def no_plan_reason(plan: Plan, time_limit: float) -> str:
    """Why ``plan`` has no phases, in words: the planner's own reason when it gives one."""
    reason = plan.stats.get("reason")
    tried = plan.stats.get("phases_tried") or []
    if plan.status == "time_limit":
        where = (
            f"after trying {', '.join(str(n) for n in tried)} phases" if tried else "before any phase count was tried"
        )
        text = f"the time limit of {time_limit:g} s ran out {where} (--time-limit gives it more)"
        return f"{text}; {reason}" if isinstance(reason, str) else text
    if isinstance(reason, str):
        return reason.replace("max_phases=", "--max-phases ")
    if plan.status == "infeasible":
        tried_text = f" ({', '.join(str(n) for n in tried)} phases tried)" if tried else ""
        return f"no plan delivers every object within the phases the planner may use{tried_text}"
    return f"the solver ended with status {plan.status}"


def _phase_row(k: int, phase: Phase) -> str:
    base = f"{phase.base[0]:6.2f}, {phase.base[1]:6.2f}"
    return (
        f"{k:>3}  {phase.action:<6}  {phase.target or '-':<12}  {phase.posture or '-':<12}  {base:<16}  "
        f"{phase.heading:<3}  {phase.holding or '-'}"
    )


def _phase_table(plan: Plan) -> str:
    header = f"{'k':>3}  {'action':<6}  {'target':<12}  {'posture':<12}  {'base [m]':<16}  {'hd':<3}  holding"
    more = "  ... and {} more phases (see the plan file)"
    return "\n".join([header, *phase_rows(plan, _phase_row, MAX_SUMMARY_PHASES, more)])


def _phases_tried(plan: Plan) -> str:
    tried = plan.stats.get("phases_tried")
    if isinstance(tried, list) and tried:
        return " (phase counts tried: " + ", ".join(str(n) for n in tried) + ")"
    return ""


def _timings(plan: Plan) -> str:
    parts = [
        f"{label} {plan.stats[key]:.3f} s"
        for key, label in (("build_s", "build"), ("solve_s", "solve"), ("total_s", "total"))
        if isinstance(plan.stats.get(key), int | float)
    ]
    return ", ".join(parts) if parts else "-"


def _plan_summary_json(
    scenario_path: Path, plan: Plan, output: Path | None, plot_path: Path | None, violations: list[str]
) -> dict[str, Any]:
    return {
        "scenario": plan.scenario,
        "scenario_path": str(scenario_path),
        "status": plan.status,
        "found": plan.found,
        "objective": plan.objective,
        "phases": [phase.to_dict() for phase in plan.phases],
        "stats": plan.stats,
        "plan_path": None if output is None else str(output),
        "plot_path": None if plot_path is None else str(plot_path),
        "violations": violations,
    }


# ---------------------------------------------------------------------- validate
def _add_validate_options(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scenario", metavar="SCENARIO", help="scenario file (JSON, fetchcarry-scenario/1)")
    parser.add_argument(
        "plan", metavar="PLAN", nargs="?", help="plan file (JSON, fetchcarry-plan/1); without it the scenario alone"
    )
    parser.add_argument(
        "--plot", metavar="PNG", help="also draw the scenario (or, with PLAN, the plan) from above into this image file"
    )
    parser.add_argument(
        "--json", action="store_true", help='print {"valid": ..., "violations": [...]} as JSON instead of text'
    )


def run_validate(args: argparse.Namespace) -> int:
    """``fetchcarry validate``: 0 valid, 1 invalid."""
    plot_path = _plot_path(args.plot)
    if args.plan is None:
        return _validate_scenario(Path(args.scenario), plot_path, args.json)
    _check_not_swapped(Path(args.scenario), Path(args.plan))
    scenario = load_scenario(Path(args.scenario))
    plan = load_plan(Path(args.plan))
    violations = validate_plan(scenario, plan)
    refused = env_refusals(scenario, plan)  # notes, not violations: the exit status does not count them
    if plot_path is not None:
        from expert.plot import plot_plan  # matplotlib only when a picture is asked for

        plot_plan(scenario, plan, plot_path)
    if args.json:
        report = {"scenario": args.scenario, "plan": args.plan, "valid": not violations, "violations": violations}
        print(json.dumps({**report, "env_refusals": refused}, indent=2))
    elif violations:
        echo(f"{args.plan}: INVALID for {args.scenario}: {len(violations)} violation(s)")
        echo("\n".join(f"  - {v}" for v in violations))
    else:
        echo(f"{args.plan}: valid for {args.scenario} ({plan.status}, {plan_length(len(plan.phases))})")
    if refused and not args.json:
        echo(f"note: the env refuses {len(refused)} phase(s) under its move and arm rules (not a format violation):")
        echo("\n".join(f"  - {r}" for r in refused))
    if plot_path is not None and not args.json:
        echo(f"plot written to {plot_path}")
    return 1 if violations else 0


def _plot_path(plot: str | None) -> Path | None:
    """The picture to draw (checked before anything is read), or ``None`` when none is asked for."""
    if plot is None:
        return None
    path = Path(plot)
    check_writable(path, "plot")
    check_plot_format(path)
    return path


def _validate_scenario(path: Path, plot_path: Path | None, as_json: bool) -> int:
    """``fetchcarry validate SCENARIO``: the scenario's rules alone; 0 valid, 1 invalid.

    A file that is not a JSON object declaring ``fetchcarry-scenario/1`` (a missing file,
    broken JSON, a plan) is bad input; a file that declares it and breaks the format's rules
    (a field, an id, an overlap) is an invalid scenario.
    """
    check_readable(path, "scenario file")
    declared = file_format(path)
    if declared == PLAN_FORMAT:
        raise InputError(
            f"{path} is a plan ({PLAN_FORMAT}), not a scenario; give its scenario first: "
            "fetchcarry validate SCENARIO PLAN"
        )
    try:
        scenario = load_scenario(path)
    except ScenarioError as error:
        if declared != SCENARIO_FORMAT:
            raise  # not a scenario file at all (not JSON, no or another format): bad input
        violations = error.violations
    else:
        violations = []
    if as_json:
        print(json.dumps({"scenario": str(path), "valid": not violations, "violations": violations}, indent=2))
    elif violations:
        echo(f"{path}: INVALID scenario: {len(violations)} violation(s) of docs/scenario-format.md")
        echo("\n".join(f"  - {v}" for v in violations))
    else:
        echo(f"{path}: valid scenario {scenario.name} ({_counts(scenario)})")
    if violations:
        if plot_path is not None:
            echo(f"fetchcarry: not drawn: {path} is not a valid scenario", file=sys.stderr)
        return 1
    if plot_path is not None:
        from expert.plot import plot_scenario  # matplotlib only when a picture is asked for

        plot_scenario(scenario, plot_path)
        if not as_json:
            echo(f"plot written to {plot_path}")
    return 0


def _counts(scenario: Scenario) -> str:
    """What ``scenario`` holds, in words: ``1 object(s), 2 table(s), 1 obstacle(s), 3 clutter``."""
    groups = (
        ("object(s)", scenario.objects),
        ("table(s)", scenario.tables),
        ("obstacle(s)", scenario.obstacles),
        ("clutter", scenario.clutter),
    )
    return ", ".join(f"{len(items)} {name}" for name, items in groups)


def _check_not_swapped(scenario_path: Path, plan_path: Path) -> None:
    """Raise ``InputError`` when the scenario argument holds a plan and the plan argument a scenario."""
    if file_format(scenario_path) == PLAN_FORMAT and file_format(plan_path) == SCENARIO_FORMAT:
        raise InputError(
            f"the two files look swapped: {scenario_path} is a plan and {plan_path} a scenario; "
            "give the scenario first: fetchcarry validate SCENARIO PLAN"
        )
