"""`plan(..., export_models=DIR)`, `fetchcarry plan --export-model DIR`: models HiGHS solves to SCIP's optimum."""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np
import pytest
from cli_run import run
from planner_cases import one_table

from expert.milp.export import MODEL_FORMAT
from expert.planner import plan
from fetchcarry_env.families import draw_paper_covered, draw_paper_multi
from fetchcarry_env.geometry import Rect

highspy = pytest.importorskip("highspy")  # in the dev extra (pyproject.toml)

EXAMPLE = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"


def highs_solve(mps: Path) -> tuple[str, float | None]:
    """HiGHS on ``mps`` with no gap tolerance: its model status and objective (None without a solution)."""
    h = highspy.Highs()
    h.silent()
    h.setOptionValue("mip_rel_gap", 0.0)
    h.setOptionValue("mip_abs_gap", 1e-9)
    assert h.readModel(str(mps)) == highspy.HighsStatus.kOk
    h.run()
    status = h.modelStatusToString(h.getModelStatus())
    value = h.getInfo().objective_function_value if status == "Optimal" else None
    return status, value


@pytest.mark.parametrize(
    "scenario",
    [draw_paper_multi(np.random.default_rng(3), 2), draw_paper_covered(np.random.default_rng(1), 2)],
    ids=["multi-2", "covered-2"],
)
def test_highs_finds_scipy_optimum_of_every_exported_model(tmp_path, scenario):
    result = plan(scenario, time_limit=60.0, export_models=tmp_path)
    assert result.status == "optimal"
    exported = [s["exported"] for s in result.stats["solves"]]
    assert exported and all((tmp_path / name).is_file() for name in exported)
    for name in exported:
        meta = json.loads((tmp_path / name).with_suffix(".json").read_text())
        assert meta["format"] == MODEL_FORMAT and meta["status"] == "optimal"
        status, value = highs_solve(tmp_path / name)
        assert status == "Optimal"
        assert math.isclose(value, meta["optimum"], rel_tol=1e-7, abs_tol=1e-6), (name, value, meta["optimum"])
    last = json.loads((tmp_path / exported[-1]).with_suffix(".json").read_text())
    assert math.isclose(last["optimum"], result.objective, abs_tol=1e-6)  # the model's optimum is the plan's Eq. 1


def test_infeasible_phase_counts_are_exported_too(tmp_path):
    """The detour case from N = 3 (no bounds): the 4-phase model is infeasible for HiGHS as for SCIP.

    The 3-phase model is refuted while it is built (no region holds a move): no model, nothing written.
    """
    scenario = one_table(obstacles=(Rect(1.2, 0.0, 1.4, 1.6),))
    result = plan(scenario, lower_bound=False, export_models=tmp_path)
    assert result.status == "optimal" and result.stats["phases_tried"] == [3, 4, 5]
    solves = {s["phases"]: s for s in result.stats["solves"]}
    assert "exported" not in solves[3] and sorted(p.name for p in tmp_path.iterdir()) == [
        "one-table_N4.json",
        "one-table_N4.mps",
        "one-table_N5.json",
        "one-table_N5.mps",
    ]
    meta = json.loads((tmp_path / "one-table_N4.json").read_text())
    assert (meta["status"], meta["optimum"]) == ("infeasible", None)
    assert highs_solve(tmp_path / "one-table_N4.mps")[0] == "Infeasible"
    assert highs_solve(tmp_path / "one-table_N5.mps")[0] == "Optimal"


def test_every_variable_has_a_meaning(tmp_path):
    scenario = draw_paper_covered(np.random.default_rng(1), 2)
    result = plan(scenario, time_limit=60.0, export_models=tmp_path)
    meta = json.loads((tmp_path / result.stats["solves"][-1]["exported"]).with_suffix(".json").read_text())
    kinds = {v["kind"] for v in meta["variables"].values()}
    assert {"base_x", "base_y", "option", "held", "delivered", "pushed"} <= kinds
    mps_columns = _mps_columns(tmp_path / result.stats["solves"][-1]["exported"])
    assert mps_columns == set(meta["variables"])
    option = next(v for v in meta["variables"].values() if v["kind"] == "option")
    assert option["action"] in ("pick", "place", "push") and len(option["box"]) == 4


def _mps_columns(path: Path) -> set[str]:
    """The column names of a free or fixed MPS file's COLUMNS section."""
    names, inside = set(), False
    for line in path.read_text().splitlines():
        if line.startswith(("ROWS", "RHS", "BOUNDS", "RANGES", "ENDATA")):
            inside = False
        if line.startswith("COLUMNS"):
            inside = True
            continue
        if inside and line.strip() and "MARKER" not in line:
            names.add(line.split()[0])
    return names


def test_cli_export_model(tmp_path, capsys):
    folder = tmp_path / "models"
    status, out, _ = run(capsys, "plan", EXAMPLE, "--export-model", folder)
    assert status == 0 and "models written:" in out
    assert sorted(p.suffix for p in folder.iterdir()) == [".json", ".mps"]
    not_a_folder = tmp_path / "file.txt"
    not_a_folder.write_text("x")
    status, _, err = run(capsys, "plan", EXAMPLE, "--export-model", not_a_folder)
    assert status == 2 and "not a folder" in err


def test_export_replaces_a_fifo_or_symlink_named_like_its_output(tmp_path):
    """A FIFO named like an output once blocked the writer for ever, and a symlink's target was overwritten.

    The planner runs in a child process, so that the old behaviour (a writer blocked on the
    FIFO) fails the test at the safety timeout instead of hanging the suite.
    """
    import os
    import subprocess
    import sys

    from expert.milp.export import export_paths
    from fetchcarry_env.scenario import Scenario

    folder, elsewhere = tmp_path / "models", tmp_path / "precious.txt"
    folder.mkdir()
    elsewhere.write_text("keep me")
    mps, meta = export_paths(folder, Scenario.load(EXAMPLE).name, 6)
    os.mkfifo(mps)
    meta.symlink_to(elsewhere)
    code = "import sys; from training.cli import main; sys.exit(main(sys.argv[1:]))"
    argv = [sys.executable, "-c", code, "plan", str(EXAMPLE), "--export-model", str(folder), "--max-phases", "6"]
    done = subprocess.run(argv, capture_output=True, text=True, timeout=300)  # a safety stop, not a speed bound
    assert done.returncode in (0, 1), done.stderr
    assert mps.is_file() and not mps.is_symlink() and mps.stat().st_size > 0
    assert meta.is_file() and not meta.is_symlink() and json.loads(meta.read_text())["format"] == MODEL_FORMAT
    assert elsewhere.read_text() == "keep me"
    assert not [p for p in folder.iterdir() if p.name.startswith(".")]  # no partial file left behind
