"""How a command ends: exceptions become a short message on stderr and an exit status.

- 2, bad input: :class:`fetchcarry_env.errors.InputError` (the one base class of the
  user's bad input: scenarios, plans, run folders, datasets, names and values), broken
  JSON, and an ``OSError`` on a file (named in the message: a missing or read-only
  file, a full disk). Nothing else: a ``ValueError`` that is not an ``InputError`` is a bug.
- 130, Ctrl-C: ``KeyboardInterrupt`` wherever it arrives.
- 143 (128 + SIGTERM, the status a shell reports for ``kill``), SIGTERM: while a command
  runs, the first SIGTERM raises :class:`Terminated`, a ``KeyboardInterrupt``, where it
  lands, so a command stops as on Ctrl-C (what finished is kept, a worker pool is stopped
  and joined, a short message); later SIGTERMs are ignored while it cleans up (SIGKILL
  still stops it at once). A SIGTERM that lands in a SCIP solve of this process takes
  effect when the solve returns (its time limit bounds it): SCIP holds the interpreter
  until then. Pool workers ignore both signals: their parent stops them.
- 3, an unexpected internal error: one line naming the error and the path of a full
  report (the traceback) written under the temporary folder; when the report cannot be
  written (no temporary folder, a file in the report folder's place), a line says so and
  the status is still 3.
- A closed output pipe (``fetchcarry dataset info ID | head``) ends quietly, the way
  the Python documentation recommends: stdout is pointed at ``/dev/null`` so that the
  interpreter's final flush does not fail again.
"""

from __future__ import annotations

import argparse
import contextlib
import datetime
import json
import os
import signal
import sys
import tempfile
import threading
import traceback
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from pathlib import Path

from fetchcarry_env.errors import InputError
from training.cli.text import printable

BAD_INPUT = 2
INTERNAL_ERROR = 3
INTERRUPTED = 130
TERMINATED = 143  # 128 + SIGTERM, what a shell reports for a process stopped by ``kill``
BROKEN_PIPE = 141  # 128 + SIGPIPE, what a shell reports for a tool whose reader went away
REPORT_FOLDER = "fetchcarry-crash-reports"  # under the system's temporary folder


class Terminated(KeyboardInterrupt):
    """SIGTERM, raised where it lands: every ``except KeyboardInterrupt`` that keeps finished work runs for it too."""


@dataclass
class Termination:
    """Whether a SIGTERM arrived while :func:`sigterm_as_interrupt` was in force."""

    received: bool = False


@contextlib.contextmanager
def sigterm_as_interrupt() -> Iterator[Termination]:
    """Within the block, the first SIGTERM raises :class:`Terminated` in the main thread; later ones are ignored.

    The handler of before comes back at the end. Outside the main thread, where Python
    cannot set a signal handler, SIGTERM keeps its handler.
    """
    termination = Termination()

    def stop(signum: int, frame: object) -> None:
        if termination.received:
            return  # already stopping: let the clean-up finish
        termination.received = True
        raise Terminated

    if threading.current_thread() is not threading.main_thread():
        yield termination
        return
    previous = signal.signal(signal.SIGTERM, stop)
    try:
        yield termination
    finally:
        signal.signal(signal.SIGTERM, previous)


def run_command(handler: Callable[[argparse.Namespace], int | None], args: argparse.Namespace) -> int:
    """``handler(args)``'s exit status, or the status of the exception it raised (and a message on stderr).

    A command stopped by SIGTERM ends with :data:`TERMINATED` (:func:`sigterm_as_interrupt`).
    """
    with sigterm_as_interrupt() as termination:
        status = _run_handler(handler, args)
    return TERMINATED if termination.received and status == INTERRUPTED else status


def _run_handler(handler: Callable[[argparse.Namespace], int | None], args: argparse.Namespace) -> int:
    """``handler(args)``'s exit status, or the status of the exception it raised (and a message on stderr)."""
    try:
        status = int(handler(args) or 0)
        sys.stdout.flush()  # a closed pipe shows here, not in the interpreter's last flush
        return status
    except KeyboardInterrupt as interrupt:
        # Objects whose construction Ctrl-C cut short (a PyBullet client half connected) complain from
        # their finalizers as the program winds down: that is noise after an interrupt, not a report.
        sys.unraisablehook = ignore_unraisable
        say("terminated" if isinstance(interrupt, Terminated) else "interrupted")
        return INTERRUPTED
    except BrokenPipeError:
        return quiet_broken_pipe()
    except InputError as error:  # the user's bad input, whatever raised it
        say(str(error))
    except json.JSONDecodeError as error:
        say(f"not valid JSON: {error}")
    except OSError as error:
        say(describe_os_error(error))
    except Exception as error:  # every other error is a bug: report it, exit 3
        say(f"internal error: {type(error).__name__}: {error}")
        try:
            say(f"the full report is in {write_report(error, args)}")
        except Exception as problem:  # a report that cannot be written does not change the status
            reason = describe_os_error(problem) if isinstance(problem, OSError) else f"{type(problem).__name__}"
            say(f"no full report could be written ({reason})")
        return INTERNAL_ERROR
    return BAD_INPUT


def ignore_unraisable(unraisable: object) -> None:
    """An ``sys.unraisablehook`` that prints nothing."""


def say(message: str) -> None:
    """One message on stderr, prefixed with the program's name."""
    print("\n".join(printable(line) for line in f"fetchcarry: {message}".split("\n")), file=sys.stderr, flush=True)


def describe_os_error(error: OSError) -> str:
    """An ``OSError`` in words, with the file it concerns."""
    reason = error.strerror or str(error)
    files = [f for f in (error.filename, error.filename2) if f is not None]
    return f"{reason}: {' -> '.join(str(f) for f in files)}" if files else reason


def quiet_broken_pipe() -> int:
    """The reader of stdout went away: stop quietly (Python's documented recipe for SIGPIPE)."""
    try:
        devnull = os.open(os.devnull, os.O_WRONLY)
        os.dup2(devnull, sys.stdout.fileno())
    except (OSError, ValueError):
        pass
    return BROKEN_PIPE


def write_report(error: BaseException, args: argparse.Namespace) -> Path:
    """Write the traceback and the command's options to a new file; return its path."""
    folder = Path(tempfile.gettempdir()) / REPORT_FOLDER
    folder.mkdir(parents=True, exist_ok=True)
    stamp = datetime.datetime.now(datetime.UTC).strftime("%Y%m%dT%H%M%SZ")
    handle, name = tempfile.mkstemp(dir=folder, prefix=f"crash-{stamp}-", suffix=".txt")
    options = {k: v for k, v in vars(args).items() if k != "handler"}
    with os.fdopen(handle, "w") as file:
        file.write(f"fetchcarry {' '.join(sys.argv[1:])}\noptions: {options!r}\npython {sys.version}\n\n")
        file.write("".join(traceback.format_exception(error)))
    return Path(name)
