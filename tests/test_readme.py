"""The Python examples of the README and of the docs pages with code run as written (from a copy of the examples)."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
BLOCKS = re.findall(r"```python\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.DOTALL)
DOCS_WITH_CODE = ("environment.md", "benchmarking.md")  # pages whose Python examples run here too
DOC_BLOCKS = [
    (page, block)
    for page in DOCS_WITH_CODE
    for block in re.findall(r"```python\n(.*?)```", (ROOT / "docs" / page).read_text(), flags=re.DOTALL)
]


def test_readme_has_python_examples():
    assert len(BLOCKS) >= 2


@pytest.mark.parametrize("index", range(len(BLOCKS)))
def test_readme_example_runs(index, tmp_path, monkeypatch):
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    exec(compile(BLOCKS[index], f"README.md block {index}", "exec"), {})


@pytest.mark.parametrize("index", range(len(DOC_BLOCKS)))
def test_docs_example_runs(index, tmp_path, monkeypatch):
    page, block = DOC_BLOCKS[index]
    shutil.copytree(ROOT / "examples", tmp_path / "examples")
    monkeypatch.chdir(tmp_path)
    exec(compile(block, f"docs/{page} block {index}", "exec"), {})


def _repository_files() -> set[Path]:
    return {p for p in ROOT.rglob("*") if ".git" not in p.parts and "__pycache__" not in p.parts}


def test_the_planner_examples_write_nothing_into_the_repository(monkeypatch, tmp_path):
    """Run from the repository itself, as a reader would: the Python and shell planner examples."""
    from training.cli import main

    planner_python = next(block for block in BLOCKS if "result.save(" in block)
    shell = re.findall(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.DOTALL)
    planner_shell = next(block for block in shell if "fetchcarry plan " in block)
    monkeypatch.chdir(ROOT)
    before = _repository_files()
    exec(compile(planner_python, "README.md planner example", "exec"), {})
    for line in planner_shell.splitlines():
        command = line.split("#")[0].strip()
        if command.startswith("fetchcarry "):
            argv = command.replace("$out", str(tmp_path)).split()[1:]
            assert main(argv) == 0, command
    assert sorted(_repository_files() - before) == []
    assert (tmp_path / "plan.json").is_file() and (tmp_path / "plan.png").is_file()


SHELL = re.findall(r"```bash\n(.*?)```", (ROOT / "README.md").read_text(), flags=re.DOTALL)
SMALLER = {"--episodes": "3"}  # the README's sizes, made small enough for the suite


def _small(command: str) -> list[str]:
    """A README command line as argv, its sizes made small (and BC trained for one epoch)."""
    argv = command.split()[1:]
    for i, word in enumerate(argv[:-1]):
        if word in SMALLER:
            argv[i + 1] = SMALLER[word]
    return [*argv, "--epochs", "1"] if argv[:2] == ["train", "bc"] else argv


@pytest.mark.slow
def test_the_dataset_training_and_benchmark_blocks_run_in_turn(monkeypatch, tmp_path):
    """The README's dataset block makes the run folder its benchmark block evaluates (at a small size).

    The dataset once recorded the env's own actions, which ``train bc`` refuses, and
    ``runs/bc-set`` came from no README command.
    """
    from training.cli import main

    data = next(block for block in SHELL if "fetchcarry generate" in block and "train bc" in block)
    bench = next(block for block in SHELL if "fetchcarry benchmark --policies" in block)
    monkeypatch.chdir(tmp_path)
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path / "datasets"))
    lines = [line.strip() for line in (data + bench).splitlines() if line.strip().startswith("fetchcarry ")]
    for command in (c for c in lines if "--scenarios my_scenarios" not in c):
        assert main(_small(command)) == 0, command
    assert (tmp_path / "bench" / "iid" / "results.json").is_file()
