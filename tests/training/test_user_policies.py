"""A user's own policy, ``package.module:factory``, in every command that takes a policy.

The factory is found from the working folder (as ``python -m`` finds a module), and what
it gives is checked: a factory that raises or returns something other than a policy, and
a policy whose ``predict`` answers something that is not an action of the env, are the
user's bad input (exit 2, naming ``module:factory``), not a crash.
"""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from collections.abc import Iterator
from pathlib import Path

import pytest

from fetchcarry_env.errors import InputError
from training.cli import main
from training.envs import make_env
from training.evaluation.results import read_results
from training.resolve import build, resolve
from training.rollout import run_episode

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "push_basic.json"
MODULE = "my_policies"
USER_MODULE = """
import numpy as np


class FirstAllowed:
    def predict(self, observation, state=None, episode_start=None, deterministic=False, action_masks=None):
        return int(np.flatnonzero(action_masks)[0]), state


class WithoutMasks:  # stable-baselines3's PPO.predict: no action_masks
    def predict(self, observation, state=None, episode_start=None, deterministic=False):
        return 0, state


class OnlyObservation:
    def predict(self, observation):
        return 0, None


class Answering:
    def __init__(self, answer):
        self.answer = answer

    def predict(self, observation, state=None, episode_start=None, deterministic=False, action_masks=None):
        return self.answer


class Failing:
    def predict(self, observation, state=None, episode_start=None, deterministic=False, action_masks=None):
        raise ZeroDivisionError("my bug")


def make_policy(env):
    return FirstAllowed()


def without_masks(env):
    return WithoutMasks()


def only_observation(env):
    return OnlyObservation()


def forty_two(env):
    return 42


def boom(env):
    raise RuntimeError("boom")


def out_of_range(env):
    return Answering((10**9, None))


def bare_action(env):
    return Answering(0)


def failing(env):
    return Failing()


not_callable = 7
"""


@pytest.fixture
def user_folder(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> Iterator[Path]:
    """A folder holding ``my_policies.py``, made the working folder; the module is forgotten afterwards."""
    folder = tmp_path / "mine"
    folder.mkdir()
    (folder / f"{MODULE}.py").write_text(USER_MODULE)
    monkeypatch.chdir(folder)
    sys.modules.pop(MODULE, None)
    yield folder
    sys.modules.pop(MODULE, None)


def _scenarios(folder: Path) -> Path:
    scenarios = folder / "scenarios"
    scenarios.mkdir()
    shutil.copy(EXAMPLE, scenarios / "example.json")
    return scenarios


def _status(argv: list[str]) -> int:
    """The exit status of ``fetchcarry argv`` (argparse's own exits raise ``SystemExit``)."""
    try:
        return main(argv)
    except SystemExit as error:
        return int(error.code)


# ------------------------------------------------------------------ the working folder
def test_the_console_script_finds_a_factory_in_the_working_folder(user_folder: Path) -> None:
    """``fetchcarry benchmark --policies my_policies:make_policy`` run from the folder of ``my_policies.py``."""
    script = Path(sys.executable).with_name("fetchcarry")
    scenarios = _scenarios(user_folder)
    argv = [str(script), "benchmark", "--policies", "my_policies:make_policy", "--scenarios", str(scenarios),
            "--out", "out", "--workers", "2", "--no-progress"]  # fmt: skip
    environment = {k: v for k, v in os.environ.items() if k != "PYTHONPATH"}
    done = subprocess.run(argv, cwd=user_folder, env=environment, capture_output=True, text=True, timeout=900)
    assert done.returncode == 0, done.stderr
    records = read_results(user_folder / "out" / "results.json")
    mine = [r for r in records if r["policy"] == "my_policies:make_policy"]
    assert len(mine) == 1 and mine[0]["phases"] > 0


def test_plan_guide_takes_a_factory_from_the_working_folder(user_folder: Path, capsys: pytest.CaptureFixture) -> None:
    path_before = list(sys.path)
    assert _status(["plan", str(EXAMPLE), "--guide", "my_policies:make_policy", "--json"]) in (0, 1)
    captured = capsys.readouterr()
    assert "No module named" not in captured.err and json.loads(captured.out)["status"]
    assert sys.path == path_before  # the working folder was on the import path for the import only


def test_a_factory_from_the_working_folder_is_built_where_the_working_folder_differs(
    user_folder: Path, monkeypatch: pytest.MonkeyPatch, tmp_path: Path
) -> None:
    """A worker whose working folder is elsewhere (Ray's) still finds the module the spec was resolved from."""
    spec = resolve("my_policies:make_policy")
    sys.modules.pop(MODULE, None)
    monkeypatch.chdir(tmp_path)
    env = make_env(spec.interface, family="basic")
    try:
        record = run_episode(env, build(spec, env), seed=0, max_steps=2, stop_on_failure=False)
    finally:
        env.close()
    assert record.figures.steps == 2


# ------------------------------------------------------------------ a factory that gives no policy
@pytest.mark.parametrize(
    ("command", "shown"),
    [
        (["benchmark", "--policies", "builtins:print", "--scenarios", "SCENARIOS", "--out", "out", "--no-progress"],
         "'builtins:print'"),
        (["plan", str(EXAMPLE), "--guide", "builtins:print"], "'builtins:print'"),
        (["benchmark", "--policies", "my_policies:forty_two", "--scenarios", "SCENARIOS", "--out", "out",
          "--no-progress"], "'my_policies:forty_two'"),
        (["plan", str(EXAMPLE), "--guide", "my_policies:boom"], "'my_policies:boom'"),
    ],
)  # fmt: skip
def test_a_factory_that_gives_no_policy_exits_2_naming_it(
    command: list[str], shown: str, user_folder: Path, capsys: pytest.CaptureFixture
) -> None:
    scenarios = str(_scenarios(user_folder))
    assert _status([scenarios if a == "SCENARIOS" else a for a in command]) == 2
    error = capsys.readouterr().err
    assert shown in error and "internal error" not in error and "Traceback" not in error


def _refusal(name: str) -> str:
    """The message of the ``InputError`` building ``name`` raises."""
    spec = resolve(name)
    env = make_env(spec.interface, family="basic")
    try:
        with pytest.raises(InputError) as raised:
            build(spec, env)
    finally:
        env.close()
    return str(raised.value)


def test_a_factory_returning_42_is_refused_naming_it_and_what_it_returned(user_folder: Path) -> None:
    message = _refusal("my_policies:forty_two")
    assert "'my_policies:forty_two'" in message and "42" in message and "predict" in message


def test_a_factory_that_raises_is_refused_with_its_error(user_folder: Path) -> None:
    message = _refusal("my_policies:boom")
    assert "'my_policies:boom'" in message and "RuntimeError: boom" in message and "my_policies.py" in message


def test_builtins_print_is_refused(user_folder: Path) -> None:
    assert "'builtins:print'" in _refusal("builtins:print")


def test_a_predict_that_cannot_take_the_protocols_keywords_is_refused(user_folder: Path) -> None:
    message = _refusal("my_policies:only_observation")
    assert "'my_policies:only_observation'" in message and "episode_start" in message


def test_a_name_that_is_not_callable_is_refused(user_folder: Path) -> None:
    with pytest.raises(InputError, match="no callable not_callable"):
        resolve("my_policies:not_callable")


# ------------------------------------------------------------------ answers during an episode
def _episode(name: str) -> object:
    spec = resolve(name)
    env = make_env(spec.interface, family="basic")
    try:
        return run_episode(env, build(spec, env), seed=0, max_steps=3, stop_on_failure=False)
    finally:
        env.close()


@pytest.mark.parametrize(
    ("name", "problem"),
    [
        ("my_policies:out_of_range", "not an action of Discrete"),
        ("my_policies:bare_action", "(action, state)"),
        ("my_policies:failing", "ZeroDivisionError: my bug"),
    ],
)
def test_a_predict_answering_no_action_is_the_users_bad_input(name: str, problem: str, user_folder: Path) -> None:
    with pytest.raises(InputError) as raised:
        _episode(name)
    assert f"'{name}'" in str(raised.value) and problem in str(raised.value)


def test_a_predict_without_action_masks_runs_without_them(user_folder: Path) -> None:
    """stable-baselines3's own ``predict`` (no ``action_masks``) is a policy: it is not handed the masks."""
    record = _episode("my_policies:without_masks")
    assert record.figures.steps == 3 and record.figures.mask_s == 0.0


def test_the_users_policy_acts_as_it_would_unwrapped(user_folder: Path) -> None:
    record = _episode("my_policies:make_policy")
    assert record.figures.steps == 3 and record.figures.invalid_actions == 0


# ------------------------------------------------------------------ the help texts
@pytest.mark.parametrize(("command", "option"), [("benchmark", "--policies"), ("plan", "--guide")])
def test_the_help_says_module_factory_imports_and_runs_the_users_code(
    command: str, option: str, capsys: pytest.CaptureFixture
) -> None:
    assert _status([command, "--help"]) == 0
    text = " ".join(capsys.readouterr().out.split())
    described = text[text.index(f"{option} ", text.index("options:")) :]
    assert "package.module:factory" in described[:700] and "imports and runs" in described[:700]
