"""Connecting to PyBullet: one private physics server per simulation, never the module-level one.

This is the only module that imports ``pybullet``; the rest of :mod:`fetchcarry_env.sim`
takes the module (for its constants) from here. The import is made quiet: PyBullet's
C code prints ``pybullet build time: ...`` when it loads (to stderr with pybullet 3.2.7,
to stdout with some builds), which would pollute command output, ``--json`` and
notebooks. File descriptors 1 and 2 are pointed at ``/dev/null`` around the import
and restored afterwards, even when the import fails.
"""

from __future__ import annotations

import contextlib
import ctypes
import functools
import importlib
import inspect
import os
import sys
from collections.abc import Iterator
from types import ModuleType

from fetchcarry_env.errors import InputError


@contextlib.contextmanager
def silenced_file_descriptors(*descriptors: int) -> Iterator[None]:
    """Send what C code writes to ``descriptors`` (1 stdout, 2 stderr) to ``/dev/null`` inside the block.

    Python's own streams are flushed first and C's stdio buffers before the descriptors
    are restored, so nothing written inside leaks out afterwards. A descriptor that is
    not open (a daemon without stdout) is left alone.
    """
    for stream in (sys.stdout, sys.stderr):
        with contextlib.suppress(Exception):
            stream.flush()
    saved: list[tuple[int, int]] = []
    devnull = os.open(os.devnull, os.O_WRONLY)
    try:
        for fd in descriptors:
            try:
                saved.append((fd, os.dup(fd)))
            except OSError:
                continue
            os.dup2(devnull, fd)
        yield
    finally:
        _flush_c_stdio()
        for fd, copy in saved:
            os.dup2(copy, fd)
            os.close(copy)
        os.close(devnull)


def _flush_c_stdio() -> None:
    """``fflush(NULL)``: write out C's buffered stdout before its descriptor is restored."""
    with contextlib.suppress(OSError, AttributeError, TypeError):
        ctypes.CDLL(None).fflush(None)


def _import_quietly(name: str) -> ModuleType:
    if name in sys.modules:
        return sys.modules[name]
    with silenced_file_descriptors(1, 2):
        return importlib.import_module(name)


pybullet = _import_quietly("pybullet")
BulletClient = _import_quietly("pybullet_utils.bullet_client").BulletClient


class QuietClient(BulletClient):
    """A :class:`BulletClient` that connects quietly and looks its functions up once.

    ``BulletClient.__init__`` always passes ``options=""``, which makes the C library print
    ``argv[0]=`` to stdout: that would corrupt machine-readable output (``--json``). This
    connects with no options instead. The stock client also builds a new
    ``functools.partial`` (the client id bound in) at every call; this one keeps each
    until :meth:`close`, which saves about 1.5 µs a call (a push stroke makes hundreds).
    Everything else (disconnect on garbage collection in the owning process) is the
    stock behaviour.
    """

    def __init__(self, gui: bool = False) -> None:
        self._shapes: dict = {}
        self._pid = os.getpid()
        self._client = pybullet.connect(pybullet.GUI if gui else pybullet.DIRECT)
        if self._client < 0:
            raise RuntimeError("could not start a PyBullet physics server")

    def __getattr__(self, name: str):
        """``pybullet.<name>`` with this client's id bound in, kept for the next call while connected."""
        attribute = getattr(pybullet, name)
        if inspect.isbuiltin(attribute):
            attribute = functools.partial(attribute, physicsClientId=self._client)
            if self._client >= 0 and name != "disconnect":
                self.__dict__[name] = attribute
        return attribute

    def __reduce__(self):
        raise TypeError(
            "a PyBullet client cannot be pickled or copied (a copy would disconnect the original); "
            "copy the environment instead, which rebuilds its own simulation"
        )

    @property
    def client_id(self) -> int:
        """The physics client id (-1 once disconnected)."""
        return self._client

    @property
    def connected(self) -> bool:
        return self._client >= 0

    def close(self) -> None:
        """Disconnect (safe to call twice)."""
        if self._client >= 0 and self._pid == os.getpid():
            # Quiet: a server with PyBullet's EGL plugin prints "Destroy EGL OpenGL window." on stdout.
            with contextlib.suppress(pybullet.error), silenced_file_descriptors(1):
                pybullet.disconnect(physicsClientId=self._client)
        self._client = -1
        # Forget the bound functions: another server may get this id, and a call must not reach it.
        for name in [k for k, v in self.__dict__.items() if isinstance(v, functools.partial)]:
            del self.__dict__[name]


def display_available() -> bool:
    """True when a PyBullet window can be opened (an X11 or Wayland display is set)."""
    return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))


def check_display() -> None:
    """Raise :class:`InputError` unless a display exists for a PyBullet window.

    ``p.GUI`` without a display makes the whole process exit without an exception, so
    this is checked before any window is opened.
    """
    if not display_available():
        raise InputError(
            "render_mode='human' needs a display (DISPLAY is not set); use render_mode='rgb_array' when headless"
        )


def connect(gui: bool = False) -> QuietClient:
    """A new physics server: headless (DIRECT), or with a window when ``gui`` (checked: a display exists)."""
    if gui:
        check_display()
    return QuietClient(gui=gui)
