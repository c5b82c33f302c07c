"""Ensembles of run folders: one policy from several networks, a run folder that stands alone, bad members refused."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import numpy as np
import pytest
import torch

from fetchcarry_env.observation import FIELDS, Capacity
from tests.cli_run import run
from training import load_policy
from training.learners.bc import BCConfig, record_demonstrations, train_bc
from training.learners.ensemble import make_ensemble


@pytest.fixture(scope="module")
def members(tmp_path_factory: pytest.TempPathFactory) -> list[Path]:
    """Two small BC runs of different seeds on the expert's first basic episodes."""
    torch.set_num_threads(1)
    demonstrations = record_demonstrations("basic", range(4))
    folder = tmp_path_factory.mktemp("members")
    for seed in (0, 1):
        train_bc(demonstrations, BCConfig(epochs=3, hidden=16, seed=seed), Capacity(), out=folder / f"bc-s{seed}")
    return [folder / "bc-s0", folder / "bc-s1"]


def test_the_ensemble_ranks_by_the_mean_of_its_members_log_probabilities(members: list[Path], tmp_path: Path):
    made = make_ensemble(members, tmp_path / "ensemble")
    loaded = load_policy(tmp_path / "ensemble")
    states = record_demonstrations("basic", range(4, 6))
    rows = torch.as_tensor(states.observations)
    with torch.inference_mode():
        expected = torch.stack([torch.log_softmax(load_policy(m).network(rows), dim=1) for m in members]).mean(0)
        torch.testing.assert_close(loaded.network(rows), expected)
        torch.testing.assert_close(loaded.scores(rows), made.scores(rows), rtol=0, atol=0)
    actions = loaded.predict(states.observations, action_masks=states.masks)[0]
    best = expected.masked_fill(~torch.as_tensor(states.masks), -torch.inf).argmax(dim=1).numpy()
    np.testing.assert_array_equal(actions, best)
    for flat, mask, action in zip(states.observations, states.masks, best, strict=True):  # one row: allowed scores only
        loaded.reset()
        assert loaded.predict(flat, action_masks=mask)[0] == action
    assert states.masks[np.arange(len(actions)), actions].all()
    config = json.loads((tmp_path / "ensemble" / "config.json").read_text())
    assert config["kind"] == "ensemble" and config["complete"] and config["config"]["avoid_returns"]
    assert [m["run"] for m in config["options"]["members"]] == [str(m) for m in members]
    # the folder stands alone: the members' weights are in it
    moved = tmp_path / "elsewhere"
    shutil.copytree(tmp_path / "ensemble", moved)
    with torch.inference_mode():
        torch.testing.assert_close(load_policy(moved).network(rows), expected)


def test_bad_members_are_refused(members: list[Path], tmp_path: Path):
    with pytest.raises(ValueError, match="at least two"):
        make_ensemble(members[:1], tmp_path / "one")
    make_ensemble(members, tmp_path / "pair")
    with pytest.raises(ValueError, match="is an ensemble"):
        make_ensemble([tmp_path / "pair", members[0]], tmp_path / "nested")
    with pytest.raises(ValueError, match="already holds a run"):
        make_ensemble(members, tmp_path / "pair")
    broken = json.loads((tmp_path / "pair" / "config.json").read_text())
    broken["options"]["members"] = broken["options"]["members"][:1]
    (tmp_path / "pair" / "config.json").write_text(json.dumps(broken))
    with pytest.raises(ValueError, match=r"options\.members"):
        load_policy(tmp_path / "pair")
    broken["options"] = ["not", "an", "object"]
    (tmp_path / "pair" / "config.json").write_text(json.dumps(broken))
    with pytest.raises(ValueError, match=r"options\.members"):
        load_policy(tmp_path / "pair")
    other = tmp_path / "other"
    shutil.copytree(members[1], other)
    config = json.loads((other / "config.json").read_text())
    config["capacity"]["objects"] += 1
    config["features"] += len(FIELDS["object"])  # a consistent config of another capacity
    (other / "config.json").write_text(json.dumps(config))
    with pytest.raises(ValueError, match="another capacity"):
        make_ensemble([members[0], other], tmp_path / "mixed")
    config["capacity"]["objects"] -= 1
    config["features"] -= len(FIELDS["object"])
    config["complete"] = False
    (other / "config.json").write_text(json.dumps(config))
    with pytest.raises(ValueError, match="not a finished run"):
        make_ensemble([members[0], other], tmp_path / "unfinished")


def test_train_ensemble_command(members: list[Path], tmp_path: Path, capsys: pytest.CaptureFixture):
    out = tmp_path / "ensemble"
    status, _, err = run(capsys, "train", "ensemble", "--members", *members, "--no-avoid-returns", "--out", out)
    assert status == 0, err
    assert json.loads((out / "config.json").read_text())["config"]["avoid_returns"] is False
    status, _, err = run(capsys, "train", "ensemble", "--members", *members, "--out", out)
    assert status == 2 and "already holds a run" in err
    status, _, err = run(capsys, "train", "ensemble", "--members", members[0], tmp_path / "nothing", "--out", "x")
    assert status == 2 and "not a run folder" in err
