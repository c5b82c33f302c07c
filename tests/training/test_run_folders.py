"""Hand-edited and hostile run folders: every one loads as before or is a RunFolderError naming its file (exit 2).

A tiny bc run is trained once; each test copies it and breaks one thing the ways a
person or a stranger might: a ``config.json`` that is a FIFO or a device, absurd counts
and sizes, deep nesting; a ``model.pt`` of random bytes, a text file, a pickle, the
wrong tensors, NaN weights. ``training.load_policy`` raises :class:`RunFolderError` (a
``ValueError``), ``fetchcarry rollout --policy DIR`` exits 2 naming the file, fast,
and no message suggests loading a file with ``weights_only`` off.
"""

from __future__ import annotations

import json
import os
import pickle
import shutil
from collections.abc import Callable
from pathlib import Path

import pytest
import torch
from cli_run import SAFETY_TIMEOUT_S, run
from fuzz.hang import hang_guard

import training
from fetchcarry_env.observation import Capacity
from training.learners import runs
from training.learners.bc import BCConfig, record_demonstrations, train_bc


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> Path:
    """A finished tiny bc run (three epochs of the expert's first basic episodes)."""
    torch.set_num_threads(1)
    folder = tmp_path_factory.mktemp("runs") / "bc"
    train_bc(record_demonstrations("basic", range(4)), BCConfig(epochs=3, hidden=16), Capacity(), out=folder)
    return folder


def _config(**changes: object) -> Callable[[Path], None]:
    """An edit of config.json: ``"capacity.objects": 10**9`` sets one nested value, ``candidates=...`` a top one."""

    def edit(folder: Path) -> None:
        file = folder / runs.CONFIG_FILE
        config = json.loads(file.read_text())
        for key, value in changes.items():
            *parents, name = key.split(".")
            target = config
            for parent in parents:
                target = target[parent]
            target[name] = value
        file.write_text(json.dumps(config))

    return edit


def _replace(name: str, make: Callable[[Path], None]) -> Callable[[Path], None]:
    def edit(folder: Path) -> None:
        (folder / name).unlink()
        make(folder / name)

    return edit


def _weights(change: Callable[[dict], object]) -> Callable[[Path], None]:
    def edit(folder: Path) -> None:
        file = folder / runs.WEIGHTS_FILE
        torch.save(change(torch.load(file, weights_only=True)), file)

    return edit


def _nan(state: dict) -> dict:
    return {k: torch.full_like(v, float("nan")) for k, v in state.items()}


def _huge_float64(state: dict) -> dict:  # finite in float64, infinite once loaded into float32
    return {k: torch.full(v.shape, 1e300, dtype=torch.float64) for k, v in state.items()}


def _wrong_shapes(state: dict) -> dict:
    return {k: torch.zeros(3, 3) for k in state}


MUTANTS: dict[str, tuple[Callable[[Path], None], str]] = {
    # config.json: file kinds and sizes (before: a hang, a hang, MemoryError after 38 s, RecursionError)
    "config FIFO": (_replace(runs.CONFIG_FILE, os.mkfifo), runs.CONFIG_FILE),
    "config /dev/zero": (_replace(runs.CONFIG_FILE, lambda p: p.symlink_to("/dev/zero")), runs.CONFIG_FILE),
    "config folder": (_replace(runs.CONFIG_FILE, Path.mkdir), runs.CONFIG_FILE),
    "config deep": (_replace(runs.CONFIG_FILE, lambda p: p.write_text("[" * 10**5 + "]" * 10**5)), runs.CONFIG_FILE),
    "config large": (_replace(runs.CONFIG_FILE, lambda p: p.write_bytes(b" " * 2**23)), runs.CONFIG_FILE),
    # config.json: counts and sizes (before: a hang in observation_layout, RuntimeError, allocation errors)
    "objects 10**9": (_config(**{"capacity.objects": 10**9}), runs.CONFIG_FILE),
    "objects -3": (_config(**{"capacity.objects": -3}), runs.CONFIG_FILE),
    "postures 0": (_config(**{"capacity.postures": 0}), runs.CONFIG_FILE),
    "hidden 10**9": (_config(**{"config.hidden": 10**9}), runs.CONFIG_FILE),
    "hidden 0": (_config(**{"config.hidden": 0}), runs.CONFIG_FILE),
    "seed 2**80": (_config(**{"config.seed": 2**80}), runs.CONFIG_FILE),
    "features 10**9": (_config(features=10**9), runs.CONFIG_FILE),
    "features 5": (_config(features=5), runs.CONFIG_FILE),
    "candidates 10**12": (_config(candidates=10**12), runs.CONFIG_FILE),
    "candidates 7": (_config(candidates=7), runs.WEIGHTS_FILE),  # a valid config: its weights do not fit
    "set encoder": (_config(**{"config.encoder": "set", "candidates": 7}), runs.CONFIG_FILE),
    # model.pt (before: UnpicklingError advising weights_only=False, IndexError, KeyError; NaN loaded)
    "model random": (lambda f: (f / runs.WEIGHTS_FILE).write_bytes(os.urandom(4096)), runs.WEIGHTS_FILE),
    "model /etc/passwd": (_replace(runs.WEIGHTS_FILE, lambda p: p.symlink_to("/etc/passwd")), runs.WEIGHTS_FILE),
    "model FIFO": (_replace(runs.WEIGHTS_FILE, os.mkfifo), runs.WEIGHTS_FILE),
    "model folder": (_replace(runs.WEIGHTS_FILE, Path.mkdir), runs.WEIGHTS_FILE),  # found by the fuzz suite
    "model pickle": (lambda f: (f / runs.WEIGHTS_FILE).write_bytes(pickle.dumps(Path("x"))), runs.WEIGHTS_FILE),
    "model empty": (lambda f: (f / runs.WEIGHTS_FILE).write_bytes(b""), runs.WEIGHTS_FILE),
    "model {}": (_weights(lambda s: {}), runs.WEIGHTS_FILE),
    "model list": (_weights(lambda s: list(s.values())), runs.WEIGHTS_FILE),
    "model wrong shapes": (_weights(_wrong_shapes), runs.WEIGHTS_FILE),
    "model NaN": (_weights(_nan), runs.WEIGHTS_FILE),
    "model float64 1e300": (_weights(_huge_float64), runs.WEIGHTS_FILE),
}


@pytest.mark.parametrize("name", MUTANTS)
def test_a_broken_run_folder_is_a_run_folder_error_naming_its_file(trained: Path, tmp_path: Path, name: str):
    edit, culprit = MUTANTS[name]
    folder = tmp_path / "run"
    shutil.copytree(trained, folder)
    edit(folder)
    with hang_guard(SAFETY_TIMEOUT_S, f"loading a run folder ({name})"), pytest.raises(runs.RunFolderError) as raised:
        training.load_policy(folder)  # a FIFO or /dev/zero read without bounds would hang: the guard fails it
    assert str(folder / culprit) in str(raised.value)
    assert "weights_only" not in str(raised.value) and len(str(raised.value)) < 600


@pytest.mark.parametrize("name", ["config FIFO", "objects 10**9", "config /dev/zero", "model pickle", "model NaN"])
def test_rollout_of_a_broken_run_folder_exits_2_naming_the_file(trained: Path, tmp_path: Path, capsys, name: str):
    edit, culprit = MUTANTS[name]
    folder = tmp_path / "run"
    shutil.copytree(trained, folder)
    edit(folder)
    status, _, err = run(capsys, "rollout", "--family", "basic", "--policy", folder)
    assert status == 2 and str(folder / culprit) in err, err
    assert "weights_only" not in err


def test_a_valid_run_folder_still_loads_and_scores_as_written(trained: Path) -> None:
    policy = training.load_policy(trained)
    saved = torch.load(trained / runs.WEIGHTS_FILE, weights_only=True)
    loaded = policy.network.state_dict()
    assert saved.keys() == loaded.keys() and all(torch.equal(saved[k], loaded[k]) for k in saved)


def test_stable_baselines3_evaluate_policy_runs_a_policy_loaded_with_its_env(trained: Path) -> None:
    from stable_baselines3.common.evaluation import evaluate_policy

    from training.envs import make_env

    env = make_env("phases", family="push", capacity=runs.read_config(trained)["capacity"])
    try:
        with pytest.raises(ValueError, match=r"load_policy\(run, env\)"):  # without its env, predict has no masks
            evaluate_policy(training.load_policy(trained), env, n_eval_episodes=1, warn=False)
        mean, spread = evaluate_policy(training.load_policy(trained, env), env, n_eval_episodes=2, warn=False)
    finally:
        env.close()
    assert mean == mean and spread >= 0  # a number: two episodes ran


def test_a_reproduction_folder_refuses_another_number_of_seeds(tmp_path: Path) -> None:
    from training.reproduce import SMOKE
    from training.reproduce.pipeline import SETTINGS_FILE, ReproduceError, check_settings

    out = tmp_path / "table"
    check_settings(out, 2, SMOKE)
    check_settings(out, 2, SMOKE)  # the same seeds: it continues
    with pytest.raises(ReproduceError, match="of 2 training seeds, not 3: run it with --seeds 2"):
        check_settings(out, 3, SMOKE)  # before: accepted; the summary said three seeds, the ensemble held two
    assert json.loads((out / SETTINGS_FILE).read_text())["seeds"] == 2
    saved = json.loads((out / SETTINGS_FILE).read_text())
    del saved["seeds"]  # a folder whose settings do not say: not refused
    (out / SETTINGS_FILE).write_text(json.dumps(saved))
    check_settings(out, 3, SMOKE)
