"""Commands start at once: each imports only what it uses, and a missing extra is named (exit 2).

Each case runs ``fetchcarry`` in a fresh interpreter and reads ``sys.modules`` at its end:
what a command imported is a property of the code, not of the machine's load.
"""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
EXAMPLE = ROOT / "examples" / "push_basic.json"
LEARNING = {"torch", "stable_baselines3", "sb3_contrib", "minari", "h5py", "ray"}
SOLVERS_AND_PLOTS = {"pyscipopt", "pybullet", "matplotlib", "scipy"}

PROBE = """
import json, sys
{block}
from training.cli import main
try:
    status = main(sys.argv[1:])
except SystemExit as exit_:
    status = exit_.code
print(json.dumps({{"status": status, "modules": sorted({{m.split(".")[0] for m in sys.modules}})}}), file=sys.stderr)
"""


def _run(tmp_path: Path, *argv: str, block: str = "") -> tuple[int, set[str], str]:
    """``fetchcarry argv...`` in a fresh interpreter: (exit status, top-level modules imported, stderr)."""
    done = subprocess.run(
        [sys.executable, "-c", PROBE.format(block=block), *argv],
        cwd=tmp_path,
        capture_output=True,
        text=True,
        timeout=600,  # a safety stop against a hang, not a speed bound
    )
    *messages, last = done.stderr.strip().splitlines()
    probe = json.loads(last)
    return probe["status"], set(probe["modules"]), "\n".join(messages)


def test_help_imports_no_command_module(tmp_path: Path) -> None:
    """``fetchcarry --help`` lists every command from the table alone: no solver, simulator, plot or learner."""
    status, modules, _ = _run(tmp_path, "--help")
    assert status == 0
    assert not modules & (LEARNING | SOLVERS_AND_PLOTS), modules & (LEARNING | SOLVERS_AND_PLOTS)


@pytest.mark.parametrize(
    "argv",
    [
        ("validate", str(EXAMPLE)),
        ("plan", str(EXAMPLE), "--time-limit", "60"),
        ("demo", "--out", "episode.png"),
        ("plan", "--help"),
    ],
    ids=["validate", "plan", "demo", "plan-help"],
)
def test_planning_commands_import_no_learning_library(tmp_path: Path, argv: tuple[str, ...]) -> None:
    """``validate``, ``plan`` and ``demo`` use neither torch, stable-baselines3 nor Minari: they do not import them."""
    status, modules, _ = _run(tmp_path, *argv)
    assert status == 0
    assert not modules & LEARNING, modules & LEARNING


def test_a_command_whose_extra_is_missing_names_it(tmp_path: Path) -> None:
    """``generate`` without Minari installed: exit 2 and the extra that brings it, not a traceback."""
    blocked = "sys.modules['minari'] = None  # as if the [train] extra were not installed"
    argv = ("generate", "--family", "basic", "--episodes", "1", "--dataset-id", "fetchcarry/none-v0")
    status, _, err = _run(tmp_path, *argv, block=blocked)
    assert status == 2, err
    assert 'pip install -e ".[train]"' in err and "minari" in err and "Traceback" not in err


def test_every_command_of_the_table_is_registered_by_its_modules() -> None:
    """The listing (:mod:`training.cli.commands`) and the full parser name the same commands."""
    from training.cli import build_parser
    from training.cli.commands import COMMANDS

    parser = build_parser()
    commands = next(a for a in parser._actions if a.dest == "command")
    assert set(commands.choices) == set(COMMANDS)
    for name, entry in COMMANDS.items():
        assert commands.choices[name].description, name  # a real parser, not the listing's placeholder
        assert next(c.help for c in commands._choices_actions if c.dest == name) == entry.help
