"""``fetchcarry generate --models``: a family's MILPs with their optima, resumable, no evaluation seeds."""

from __future__ import annotations

import json
import math
from pathlib import Path

import pytest
from cli_run import run

from expert.milp.export import MODEL_FORMAT
from expert.plans import Plan
from fetchcarry_env.scenario import Scenario
from training.data.models import INDEX, CollectionConfig, generate_models

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"
FAMILY = "objects-2"  # two objects: a second or two per scenario


def test_two_scenarios_with_an_optimum_highs_finds(tmp_path, capsys):
    out = tmp_path / "models"
    status, stdout, _ = run(
        capsys, "generate", "--models", "--family", FAMILY, "--episodes", 2, "--seed", 5, "--out", out,
        "--time-limit", 60, "--no-progress", "--json",
    )  # fmt: skip
    assert status == 0, stdout
    summary = json.loads(stdout)
    assert summary["generated"] == 2 and summary["proven_optimal"] == 2
    index = json.loads((out / INDEX).read_text())
    assert [e["seed"] for e in index["scenarios"]] == [5, 6]
    for entry in index["scenarios"]:
        folder = out / f"seed-{entry['seed']}"
        scenario = Scenario.load(folder / "scenario.json")
        assert scenario.name == entry["scenario"]
        assert Plan.load(folder / "plan.json").objective == pytest.approx(entry["objective"])
        assert entry["models"] and all((out / m["mps"]).is_file() for m in entry["models"])
    last = index["scenarios"][0]["models"][-1]
    meta = json.loads((out / last["mps"]).with_suffix(".json").read_text())
    assert meta["format"] == MODEL_FORMAT and meta["status"] == "optimal"
    assert meta["optimum"] == pytest.approx(index["scenarios"][0]["objective"], abs=1e-6)
    highspy = pytest.importorskip("highspy")  # in the dev extra (pyproject.toml)
    h = highspy.Highs()
    h.silent()
    h.setOptionValue("mip_rel_gap", 0.0)
    h.setOptionValue("mip_abs_gap", 1e-9)
    assert h.readModel(str(out / last["mps"])) == highspy.HighsStatus.kOk
    h.run()
    assert h.modelStatusToString(h.getModelStatus()) == "Optimal"
    assert math.isclose(h.getInfo().objective_function_value, meta["optimum"], rel_tol=1e-7, abs_tol=1e-6)


def test_an_interrupted_collection_keeps_its_seeds_and_resumes(tmp_path):
    out = tmp_path / "models"
    config = CollectionConfig(FAMILY, 20, 3, time_limit=60.0)

    def stop_after_first(index: int, entry: dict) -> None:
        if index == 0:
            raise KeyboardInterrupt

    with pytest.raises(KeyboardInterrupt):
        generate_models(config, out, progress=False, on_seed=stop_after_first)
    kept = json.loads((out / INDEX).read_text())["scenarios"]
    assert [e["seed"] for e in kept] == [20]
    first = (out / "seed-20" / "plan.json").read_bytes()
    report = generate_models(config, out, progress=False)
    assert (report.resumed, report.generated) == (1, 2)
    assert (out / "seed-20" / "plan.json").read_bytes() == first  # kept, not made again
    assert [e["seed"] for e in json.loads((out / INDEX).read_text())["scenarios"]] == [20, 21, 22]


@pytest.mark.parametrize(
    "argv, message",
    [
        (["--seed", 999_999_999], "evaluation seeds"),
        (["--scenario", str(EXAMPLE)], "--family"),
        (["--dataset-id", "fetchcarry/x-v0"], "not --dataset-id"),
    ],
)
def test_bad_input_is_refused(tmp_path, capsys, argv, message):
    family = [] if "--scenario" in argv else ["--family", FAMILY]
    status, _, err = run(capsys, "generate", "--models", *family, "--episodes", 2, "--out", tmp_path / "m", *argv)
    assert status == 2 and message in err
    assert not (tmp_path / "m" / INDEX).exists()


def test_another_collection_in_the_folder_is_refused(tmp_path, capsys):
    out = tmp_path / "models"
    generate_models(CollectionConfig(FAMILY, 5, 1, time_limit=60.0), out, progress=False)
    status, _, err = run(capsys, "generate", "--models", "--family", FAMILY, "--episodes", 1, "--seed", 6, "--out", out)
    assert status == 2 and "other options (seed" in err
