"""Which picture files an episode can be drawn into, and at what size the env renders for each.

Light on purpose (no matplotlib, no Pillow): the command line checks a picture's path
and picks the env's render size before it runs the episode, then draws it with
:mod:`training.pictures.episode`.
"""

from __future__ import annotations

from pathlib import Path

from fetchcarry_env.errors import InputError

STILL_SUFFIXES = (".png", ".jpg", ".jpeg", ".svg", ".pdf")
# The env's render size for a still picture: the strip crops it, so it is rendered large.
STILL_RENDER_SIZE = (1024, 768)  # pixels (width, height)
GIF_RENDER_SIZE = (1024, 768)  # pixels (width, height) the env renders a GIF's frames at, before the crop


def check_picture_path(path: str | Path) -> Path:
    """``path`` as a Path, or :class:`InputError` when its suffix is not a picture format the episode pictures write."""
    path = Path(path)
    if path.suffix.lower() not in (".gif", *STILL_SUFFIXES):
        raise InputError(f"cannot write a picture to {path}: use a .gif, {', '.join(STILL_SUFFIXES)} file")
    return path


def is_gif(path: str | Path) -> bool:
    """Whether ``path`` names an animated GIF (every state) rather than a still picture."""
    return Path(path).suffix.lower() == ".gif"


def render_size(path: str | Path) -> tuple[int, int]:
    """The env's render size (pixels: width, height) for a picture written to ``path``."""
    return GIF_RENDER_SIZE if is_gif(path) else STILL_RENDER_SIZE
