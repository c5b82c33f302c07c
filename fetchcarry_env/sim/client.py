"""Connecting to PyBullet: one private physics server per simulation, never the module-level one."""

from __future__ import annotations

import contextlib
import os

import pybullet
from pybullet_utils.bullet_client import BulletClient

from fetchcarry_env.errors import UsageError


class QuietClient(BulletClient):
    """A :class:`BulletClient` that connects without the ``argv[0]=`` line the stock one prints on stdout.

    ``BulletClient.__init__`` always passes ``options=""``, which makes the C library print
    ``argv[0]=`` to stdout: that would corrupt machine-readable output (``--json``). This
    connects with no options instead; everything else (client-id injection, disconnect on
    garbage collection in the owning process) is the stock behaviour.
    """

    def __init__(self, gui: bool = False) -> None:
        self._shapes: dict = {}
        self._pid = os.getpid()
        self._client = pybullet.connect(pybullet.GUI if gui else pybullet.DIRECT)
        if self._client < 0:
            raise RuntimeError("could not start a PyBullet physics server")

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
            with contextlib.suppress(pybullet.error):
                pybullet.disconnect(physicsClientId=self._client)
        self._client = -1


def check_display() -> None:
    """Raise :class:`UsageError` unless a display exists for a PyBullet window.

    ``p.GUI`` without a display makes the whole process exit without an exception, so
    this is checked before any window is opened.
    """
    if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
        raise UsageError(
            "render_mode='human' needs a display (DISPLAY is not set); use render_mode='rgb_array' when headless"
        )


def connect(gui: bool = False) -> QuietClient:
    """A new physics server: headless (DIRECT), or with a window when ``gui`` (checked: a display exists)."""
    if gui:
        check_display()
    return QuietClient(gui=gui)
