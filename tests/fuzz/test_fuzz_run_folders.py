"""The fuzz suite for run folders: a mutated run folder loads as a policy or is a RunFolderError, fast.

Three tiny run folders are trained once (a flat MLP, a set encoder, their ensemble);
each example copies one and breaks it: its ``config.json`` mutated (:mod:`mutations`:
wrong types, absurd numbers, deleted and unknown keys, deep nesting, mangled bytes), its
``model.pt`` mangled (cut short, bytes flipped, random, a pickle of other objects, the
wrong tensors, NaN, another dtype), or either file swapped for a FIFO, a device, a
folder or a link. ``training.load_policy`` then returns a policy that acts (one
decision on a zero observation) or raises :class:`RunFolderError` naming the folder,
never another exception, never advice to turn ``weights_only`` off, and never hangs:
every example runs under an alarm (:data:`HANG_SECONDS`), a safety timeout, not a speed bound.
"""

from __future__ import annotations

import io
import json
import os
import pickle
import shutil
import tempfile
from dataclasses import replace
from pathlib import Path

import numpy as np
import pytest
import torch
from cli_run import SAFETY_TIMEOUT_S
from hang import hang_guard
from hypothesis import given, settings
from hypothesis import strategies as st
from mutations import file_bytes, mutated, to_json_text
from test_fuzz_inputs import fuzz

import training
from fetchcarry_env.observation import Capacity
from training.learners import runs
from training.learners.bc import BCConfig, record_demonstrations, train_bc
from training.learners.ensemble import make_ensemble

HANG_SECONDS = SAFETY_TIMEOUT_S  # an example still running after this is a hang: it fails instead of blocking
DEADLINE = None  # no per-example time bound: a loaded machine would break it (a load takes some 0.1 s alone)
KINDS = ("mlp", "set", "ensemble")


@pytest.fixture(scope="module")
def trained(tmp_path_factory: pytest.TempPathFactory) -> dict[str, Path]:
    """A finished flat-MLP run, a set-encoder run and their ensemble (tiny: three epochs of four episodes)."""
    torch.set_num_threads(1)
    root = tmp_path_factory.mktemp("fuzz-runs")
    demonstrations = record_demonstrations("basic", range(4))
    train_bc(demonstrations, BCConfig(epochs=2, hidden=16), Capacity(), out=root / "mlp")
    config = BCConfig(epochs=2, hidden=16, encoder="set", avoid_returns=True, push_after_approach=True)
    train_bc(demonstrations, config, Capacity(), out=root / "set")
    make_ensemble([root / "mlp", root / "set"], root / "ensemble")
    return {kind: root / kind for kind in KINDS}


def _copy(trained: dict[str, Path], kind: str) -> Path:
    folder = Path(tempfile.mkdtemp(dir=trained[kind].parent)) / kind
    shutil.copytree(trained[kind], folder)
    return folder


def check_loads_or_refuses(folder: Path) -> None:
    """``load_policy(folder)`` gives a policy that acts, or a RunFolderError naming the folder; nothing else."""
    with hang_guard(HANG_SECONDS, "loading a run folder"):
        try:
            policy = training.load_policy(folder)
        except runs.RunFolderError as error:
            message = str(error)
            assert str(folder) in message and "weights_only" not in message, message
            assert "\x1b" not in message and len(message) < 2_000, message
            message.encode("utf-8")
            return
        saved = runs.read_config(folder)
        observation = np.zeros(saved["features"], np.float32)
        action, _ = policy.predict(observation, action_masks=np.ones(saved["candidates"], bool))
        assert 0 <= int(action) < saved["candidates"]
    shutil.rmtree(folder.parent)


# ---------------------------------------------------------------------------- config.json
@settings(fuzz(150), deadline=DEADLINE)
@given(data=st.data())
def test_fuzz_a_mutated_config_json_loads_or_is_a_run_folder_error(trained, data):
    kind = data.draw(st.sampled_from(KINDS))
    folder = _copy(trained, kind)
    config = json.loads((folder / runs.CONFIG_FILE).read_text())
    document = data.draw(mutated(config, max_mutations=3))
    (folder / runs.CONFIG_FILE).write_bytes(data.draw(file_bytes(to_json_text(document))))
    check_loads_or_refuses(folder)


# ---------------------------------------------------------------------------- model.pt
def _tensor_mutant(draw: st.DrawFn, state: dict[str, torch.Tensor]) -> object:
    """The network's tensors with one thing wrong (or, sometimes, not a dict of tensors at all)."""
    names = sorted(state)
    name = draw(st.sampled_from(names))
    how = draw(st.sampled_from(["drop", "extra", "reshape", "nan", "inf", "huge", "dtype", "int", "scalar",
                                "string", "list", "empty", "nested"]))  # fmt: skip
    state = dict(state)
    tensor = state[name]
    if how == "drop":
        del state[name]
    elif how == "extra":
        state[name + ".extra"] = torch.zeros(2)
    elif how == "reshape":
        state[name] = tensor.reshape(-1)[: max(1, tensor.numel() - 1)]
    elif how in ("nan", "inf"):
        state[name] = tensor.clone().reshape(-1).index_fill(0, torch.tensor([0]), float(how)).reshape(tensor.shape)
    elif how == "huge":
        state[name] = torch.full(tensor.shape, 1e300, dtype=torch.float64)
    elif how == "dtype":
        state[name] = tensor.double()
    elif how == "int":
        state[name] = tensor.long()
    elif how == "scalar":
        state[name] = 3
    elif how == "string":
        state[name] = "weights"
    elif how == "list":
        return list(state.values())
    elif how == "empty":
        return {}
    elif how == "nested":
        return {"network": state}
    return state


@st.composite
def model_bytes(draw: st.DrawFn, file: Path) -> bytes:
    """The bytes of a mangled ``model.pt``: cut, flipped, random, a pickle, or the wrong tensors saved properly."""
    raw = file.read_bytes()
    how = draw(st.sampled_from(["cut", "flip", "random", "pickle", "tensors", "tensors", "tensors", "empty"]))
    if how == "cut":
        return raw[: draw(st.integers(0, len(raw) - 1))]
    if how == "flip":
        at = draw(st.integers(0, len(raw) - 1))
        return raw[:at] + bytes([raw[at] ^ draw(st.integers(1, 255))]) + raw[at + 1 :]
    if how == "random":
        return draw(st.binary(min_size=1, max_size=2048))
    if how == "pickle":
        return pickle.dumps(draw(st.sampled_from([Path("x"), os.getcwd, {"a": [1, 2]}, replace])))
    if how == "empty":
        return b""
    buffer = io.BytesIO()
    torch.save(_tensor_mutant(draw, torch.load(file, weights_only=True)), buffer)
    return buffer.getvalue()


@settings(fuzz(150), deadline=DEADLINE)
@given(data=st.data())
def test_fuzz_a_mangled_model_pt_loads_or_is_a_run_folder_error(trained, data):
    folder = _copy(trained, data.draw(st.sampled_from(KINDS)))
    (folder / runs.WEIGHTS_FILE).write_bytes(data.draw(model_bytes(folder / runs.WEIGHTS_FILE)))
    check_loads_or_refuses(folder)


# ---------------------------------------------------------------------------- file kinds
@settings(fuzz(24), deadline=DEADLINE)
@given(data=st.data())
def test_fuzz_a_run_folder_file_of_another_kind_is_a_run_folder_error(trained, data):
    folder = _copy(trained, data.draw(st.sampled_from(KINDS)))
    file = folder / data.draw(st.sampled_from([runs.CONFIG_FILE, runs.WEIGHTS_FILE]))
    file.unlink()
    swap = data.draw(st.sampled_from(["fifo", "dev-zero", "dev-null", "folder", "dangling", "loop", "passwd"]))
    if swap == "fifo":
        os.mkfifo(file)
    elif swap == "dev-zero":
        file.symlink_to("/dev/zero")
    elif swap == "dev-null":
        file.symlink_to("/dev/null")
    elif swap == "folder":
        file.mkdir()
    elif swap == "dangling":
        file.symlink_to(folder / "nowhere")
    elif swap == "loop":
        file.symlink_to(file)
    else:
        file.symlink_to("/etc/passwd")
    check_loads_or_refuses(folder)
