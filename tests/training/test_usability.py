"""Small usability fixes of issue 8, section 6: reasons, swapped files, help texts, names, escaping."""

from __future__ import annotations

import json
from pathlib import Path

import pytest
from cli_run import bench, run

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "push_basic.json"


@pytest.mark.parametrize(
    ("options", "why"),
    [
        (["--max-phases", "3"], "why        --max-phases 3 is below the lower bound"),
        (["--time-limit", "0.0001"], "why        the time limit of 0.0001 s ran out"),
    ],
)
def test_plan_says_why_there_is_no_plan(capsys, tmp_path: Path, options: list[str], why: str) -> None:
    status, out, _ = run(capsys, "plan", EXAMPLE, "-o", tmp_path / "p.json", *options)
    assert status == 1 and why in out


def test_rollout_says_why_the_expert_could_not_act(capsys) -> None:
    status, out, _ = run(capsys, "rollout", "--scenario", EXAMPLE, "--time-limit", "0.0001")
    assert status == 1 and "why        the planner found no plan within its time limit of 0.0001 s" in out


def test_validate_with_the_files_swapped_says_so(capsys, tmp_path: Path) -> None:
    plan_file = tmp_path / "p.json"
    assert run(capsys, "plan", EXAMPLE, "-o", plan_file)[0] == 0
    status, out, err = run(capsys, "validate", plan_file, EXAMPLE)
    assert status == 2 and out == "" and "the two files look swapped" in err


def test_demo_help_shows_the_defaults(capsys) -> None:
    status, out, _ = run(capsys, "demo", "--help")
    assert status == 0 and "default episode.png" in out and "default 7" in out


@pytest.mark.parametrize("command", [["plan"], ["validate"], ["rollout"], ["generate"], ["demo"], ["env"]])
def test_help_texts_point_to_no_private_documents(capsys, command: list[str]) -> None:
    status, out, _ = (bench if command == ["env"] else run)(capsys, *command, "--help")
    assert status == 0 and "spec/" not in out and "``" not in out and ":mod:" not in out


def test_the_figures_use_the_env_info_names_and_explain_return_and_objective(capsys) -> None:
    status, out, _ = run(capsys, "rollout", "--family", "multi", "--seed", "3")
    assert status == 0
    assert "collisions 0, invalid actions 0" in out and "contacts" not in out and "refused" not in out
    (ret,) = [line for line in out.splitlines() if line.startswith("return ")]
    (objective,) = [line for line in out.splitlines() if line.startswith("objective ")]
    assert "minus the episode's task cost" in ret and "the task cost of the first plan" in objective
    status, out, _ = run(capsys, "rollout", "--family", "multi", "--seed", "3", "--json")
    figures = json.loads(out)
    assert {"collisions", "invalid_actions", "episode_return", "objective"} <= set(figures)
    assert figures["episode_return"] == pytest.approx(-figures["objective"], abs=1e-6)  # one quantity, both sides


def test_control_characters_in_names_are_shown_escaped(capsys, tmp_path: Path) -> None:
    scenario = json.loads(EXAMPLE.read_text())
    scenario["name"] = "evil\x1b[2J\x1b[31mred\u202e"
    path = tmp_path / "evil.json"
    path.write_text(json.dumps(scenario))
    status, out, _ = run(capsys, "plan", path, "-o", tmp_path / "p.json")
    assert status == 0 and "\x1b" not in out and "\u202e" not in out
    assert "evil\\x1b[2J\\x1b[31mred\\u202e" in out
    status, out, _ = run(capsys, "rollout", "--scenario", path)
    assert "\x1b" not in out and "evil\\x1b[2J" in out


# ---------------------------------------------------------------------- what a new user tripped on
def _commands(parser, prefix: tuple[str, ...] = ()) -> list[tuple[str, ...]]:
    """Every (sub)command of ``parser`` as the words that name it."""
    import argparse

    out = [prefix]
    for action in parser._actions:
        if isinstance(action, argparse._SubParsersAction):
            for name, sub in action.choices.items():
                out += _commands(sub, (*prefix, name))
    return out


def test_no_help_text_shows_an_escaped_percent(capsys) -> None:
    """``bench anytime --help`` printed "within 5 %% of": a %-escape in a text argparse never formats."""
    from benchmarks.cli import build_parser as benchmarks_parser
    from training.cli import build_parser

    benchmarks = _commands(benchmarks_parser())
    assert ("anytime",) in benchmarks
    for runner, commands in ((run, _commands(build_parser())), (bench, benchmarks)):
        for command in commands:
            status, out, _ = runner(capsys, *command, "--help")
            assert status == 0 and "%%" not in out, command


def test_fetchcarry_bench_says_where_the_benchmarks_went(capsys) -> None:
    status, out, err = run(capsys, "bench", "env")
    assert status == 2 and out == "" and "python -m benchmarks --help" in err


def test_the_docs_say_which_mask_env_unwrapped_gives() -> None:
    """``env.unwrapped.action_masks()`` of the phases env has 294 entries, not 4,080: docs/environment.md says so."""
    import gymnasium as gym

    import fetchcarry_env  # noqa: F401  (registers the envs)

    readme = " ".join((ROOT / "docs" / "environment.md").read_text().split())
    env = gym.make("FetchCarryPushPhases-v0", family="basic")
    try:
        env.reset(seed=0)
        inner, outer = env.unwrapped.action_masks().shape[0], env.get_wrapper_attr("action_masks")().shape[0]
        assert f"`env.unwrapped.action_masks()` has {inner} entries" in readme and f"not {outer:,}" in readme
        with pytest.raises(AttributeError):
            env.action_masks()
        assert "`env.action_masks()` on what `gym.make` returns is an `AttributeError`" in readme
    finally:
        env.close()


def test_the_readme_says_how_to_get_the_cpu_build_of_torch_elsewhere() -> None:
    readme = " ".join((ROOT / "README.md").read_text().split())
    installing = readme.split("## Installing", 1)[1].split("## ", 1)[0]
    assert "pip install torch==2.13.0 --index-url https://download.pytorch.org/whl/cpu" in installing
    assert "A CUDA build works too" in installing
