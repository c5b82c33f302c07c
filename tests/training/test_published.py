"""Run folders that ship with the repository: loadable by name, each with its card, reproducing its records."""

from __future__ import annotations

from pathlib import Path

import pytest

from training.cli import main
from training.evaluation.results import read_results, write_results
from training.published import FOLDER, published_names, published_run
from training.resolve import resolve

ROOT = Path(__file__).resolve().parents[2]
RECORDS = ROOT / "docs" / "benchmarks" / "perturbed-factors" / "results.json.gz"


def test_every_published_run_loads_by_name_and_has_a_card_with_its_recipe_scores_and_commands() -> None:
    assert published_names() == ["bc-mlp", "bc-set"]
    for name in published_names():
        spec = resolve(f"{name}@published")
        assert spec.name == name and spec.interface == "phases" and Path(spec.run) == FOLDER / name
        files = {p.name for p in published_run(name).iterdir()}
        assert files == {"card.md", "config.json", "model.pt", "metrics.csv"}  # no training checkpoint
        card = (FOLDER / name / "card.md").read_text()
        for section in ("**Data**", "**Recipe**", "**Training seed**", "## Scores", f"--policies {name}@published"):
            assert section in card, (name, section)


def test_an_unknown_published_name_is_refused_naming_the_published_ones(capsys: pytest.CaptureFixture) -> None:
    argv = ["benchmark", "--policies", "bc-nope@published", "--split", "iid", "--episodes", "1", "--out", "x"]
    assert main([*argv, "--no-progress"]) == 2
    assert "no published run 'bc-nope'; published: bc-mlp, bc-set" in capsys.readouterr().err


def test_benchmark_check_reproduces_the_published_runs_records(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    records = [r for r in read_results(RECORDS) if r["policy"] in published_names()]
    assert len(records) == 1000  # 100 episodes of five splits each
    sample = [r for r in records if r["seed"] % 50 == 0]  # two episodes of every split, each network
    write_results(tmp_path / "sample.json", sample)
    argv = ["benchmark", "--check", str(tmp_path / "sample.json"), "--no-progress", "--policies"]
    assert main([*argv, *(f"{name}@published" for name in published_names())]) == 0
    assert f"{len(sample)} of {len(sample)} records identical" in capsys.readouterr().out
