"""The ``fetchcarry`` command line run in-process, as every CLI test runs it."""

from __future__ import annotations

import pytest

from training.cli import main


def run(capsys: pytest.CaptureFixture, *argv: object) -> tuple[int, str, str]:
    """``fetchcarry argv...`` in this process: (exit status, stdout, stderr); argparse's own exits included.

    Fails the test on any traceback in stderr: a command never prints one.
    """
    try:
        status = main([str(a) for a in argv])
    except SystemExit as exit_:
        status = exit_.code
    out, err = capsys.readouterr()
    assert "Traceback" not in err
    return status, out, err
