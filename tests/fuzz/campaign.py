"""A longer fuzz campaign than the test suite runs: counts of what happens to mutated files, by outcome.

Run from the repository root::

    PYTHONPATH=. python tests/fuzz/campaign.py --examples 2000

It draws mutated scenario files, plan files and (scenario, plan) pairs for
``fetchcarry validate`` with the strategies of :mod:`mutations` (derandomized: the
same files every run) and prints, for each, how many ended in each outcome. A crash
is any exception other than the documented one (or an exit status other than 0, 1, 2,
or a traceback on stderr); the campaign lists the first few of them.
"""

from __future__ import annotations

import argparse
import contextlib
import io
import sys
import tempfile
from collections import Counter
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

sys.path.insert(0, str(Path(__file__).resolve().parent))

from mutations import file_bytes, mutated, to_json_text
from test_fuzz_inputs import PLAN_FILE, SCENARIO, VALID_PLAN, VALID_SCENARIO

from expert.plans import Plan, PlanFormatError
from expert.validate import validate_plan
from fetchcarry_env.scenario import Scenario, ScenarioError
from training.cli import main


def _kind(message: str) -> str:
    """The category of a violation message: its rule, or the kind of format problem."""
    head = message.split(":")[0]
    if head.startswith(("rule ", "structure")):
        return head
    for words in ("not a text file", "not a UTF-8", "nested too deeply", "not valid JSON", "unknown key", "bytes"):
        if words in message:
            return f"format ({words})"
    return "format (wrong or missing value)"


def campaign(examples: int, workdir: Path) -> dict[str, Counter]:
    counts: dict[str, Counter] = {"scenario": Counter(), "plan": Counter(), "validate": Counter()}
    crashes: list[str] = []
    config = settings(
        max_examples=examples,
        derandomize=True,
        database=None,
        deadline=None,
        suppress_health_check=list(HealthCheck),
    )

    @config
    @given(data=st.data())
    def scenarios(data):
        path = workdir / "s.json"
        path.write_bytes(data.draw(file_bytes(to_json_text(data.draw(mutated(VALID_SCENARIO))))))
        try:
            Scenario.load(path)
            counts["scenario"]["accepted"] += 1
        except ScenarioError as error:
            counts["scenario"][f"ScenarioError: {_kind(error.violations[0])}"] += 1
        except Exception as error:
            counts["scenario"]["CRASH"] += 1
            crashes.append(f"scenario: {type(error).__name__}: {str(error)[:200]}")

    @config
    @given(data=st.data())
    def plans(data):
        path = workdir / "p.json"
        path.write_bytes(data.draw(file_bytes(to_json_text(data.draw(mutated(VALID_PLAN))))))
        try:
            violations = validate_plan(SCENARIO, Plan.load(path))
            counts["plan"]["read, valid" if not violations else f"read, invalid: {_kind(violations[0])}"] += 1
        except PlanFormatError:
            counts["plan"]["PlanFormatError"] += 1
        except Exception as error:
            counts["plan"]["CRASH"] += 1
            crashes.append(f"plan: {type(error).__name__}: {str(error)[:200]}")

    @config
    @given(data=st.data(), which=st.sampled_from(["scenario", "plan", "both"]))
    def cli(data, which):
        scenario_text, plan_text = to_json_text(VALID_SCENARIO), to_json_text(VALID_PLAN)
        if which != "plan":
            scenario_text = to_json_text(data.draw(mutated(VALID_SCENARIO)))
        if which != "scenario":
            plan_text = to_json_text(data.draw(mutated(VALID_PLAN)))
        (workdir / "cs.json").write_bytes(data.draw(file_bytes(scenario_text)))
        (workdir / "cp.json").write_bytes(data.draw(file_bytes(plan_text)))
        err = io.StringIO()
        try:
            with contextlib.redirect_stdout(io.StringIO()), contextlib.redirect_stderr(err):
                status = main(["validate", str(workdir / "cs.json"), str(workdir / "cp.json")])
        except SystemExit as exit_:
            status = exit_.code
        except Exception as error:
            status = f"CRASH ({type(error).__name__})"
            crashes.append(f"validate: {type(error).__name__}: {str(error)[:200]}")
        if "Traceback" in err.getvalue():
            status = f"{status} with a traceback"
        counts["validate"][f"exit {status}"] += 1

    scenarios()
    plans()
    cli()
    counts["crashes"] = Counter(crashes[:10])
    return counts


def main_(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--examples", type=int, default=1000, help="files drawn for each of the three targets")
    args = parser.parse_args(argv)
    with tempfile.TemporaryDirectory() as folder:
        counts = campaign(args.examples, Path(folder))
    for target, counter in counts.items():
        print(f"{target} ({sum(counter.values())})")
        for outcome, count in counter.most_common():
            print(f"  {count:6d}  {outcome}")
    print(f"starting points: {PLAN_FILE.name} and examples/push_basic.json")
    return 1 if counts["crashes"] else 0


if __name__ == "__main__":
    sys.exit(main_())
