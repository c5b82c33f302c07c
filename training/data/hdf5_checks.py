"""The checks of a dataset's HDF5 file (``main_data.hdf5``) before Minari, or anything else, reads its episodes.

An HDF5 file can make its reader read elsewhere: an *external link* names a path in
another file (a FIFO there blocks the reader for good), a *soft link* names a path in
the same file (itself, and the reader gives up deep in the library), *external raw
storage* keeps a dataset's bytes in another file (``/dev/zero``, a file of the user's),
and a *virtual dataset* maps other datasets, of any file, into one. A dataset may also
declare a shape far larger than what it stores (unwritten chunks read as zeros), so
that reading it exhausts memory. This project's datasets hold none of these: Minari
writes plain groups and datasets, one hard link each, uncompressed, their rows counted
by each episode's ``total_steps`` attribute.

:func:`check_episode_file` walks the file's links with ``H5Lvisit``, which reports
each link's kind without following it, before it opens any object; it stops after
:data:`MAX_LINKS_PER_EPISODE` links in one episode or :data:`MAX_HDF5_LINKS` in all, so
a file of millions of groups is refused quickly. Only then does it open the objects
(through hard links only) to check each dataset's storage, rows, trailing shape (those
of the recorded spaces), element type and the bytes it declares. Every refusal is an
:class:`EpisodeFileError` naming the episode and the object.
"""

from __future__ import annotations

import math
import os
import stat
from dataclasses import dataclass, field
from pathlib import Path

import gymnasium as gym
import h5py
import numpy as np
from minari.dataset.minari_storage import is_image_space

from fetchcarry_env.errors import InputError

MAX_HDF5_LINKS = 1_000_000  # links in one file (a phases dataset has 21 an episode: some 47,000 episodes)
MAX_LINKS_PER_EPISODE = 64  # links under one episode (a phases episode has 20, with images 21 or 22)
MAX_EPISODE_ATTRIBUTES = 256  # attributes of an episode group (Minari's and this project's figures: 26)
STEP_MEMBERS = ("actions", "rewards", "terminations", "truncations")  # one row per step
STATE_MEMBERS = ("observations", "infos")  # one row per state: the steps and the first state
NUMERIC_KINDS = "biuf"  # numpy dtype kinds of the arrays a dataset holds: bool, integers, floats
_LINK_KINDS = {h5py.h5l.TYPE_SOFT: "a soft link", h5py.h5l.TYPE_EXTERNAL: "an external link"}
Layout = dict[str, tuple[int, ...] | None]  # an episode's datasets (paths in its group) -> rows' shape (None: any)


class EpisodeFileError(InputError):
    """An HDF5 file of episodes that is not what Minari writes for this project; names the episode and object."""


class EpisodeCountError(EpisodeFileError):
    """The file's episodes or steps are not those ``metadata.json`` counts (either file may be the edited one)."""


@dataclass(frozen=True)
class Spaces:
    """What the episodes were recorded with: the spaces of ``metadata.json`` and whether images are JPEG bytes."""

    observation: gym.Space
    action: gym.Space
    jpeg_encoding: bool = True


@dataclass
class _LinkWalk:
    """``H5Lvisit``'s callback: collects hard links' names, stops at another kind of link or beyond ``limit``."""

    limit: int
    names: list[bytes] = field(default_factory=list)
    other: tuple[bytes, int] | None = None  # the first link that is not a hard link: its name and kind

    def __call__(self, name: bytes, info: h5py.h5l.LinkInfo) -> bool | None:
        """Record one link; a true value stops the walk (the callback must not raise: h5py would not pass it on)."""
        if info.type != h5py.h5l.TYPE_HARD:
            self.other = (name, info.type)
            return True
        self.names.append(name)
        return True if len(self.names) > self.limit else None


def check_episode_file(path: Path, episodes: int, total_steps: int, spaces: Spaces) -> None:
    """Raise :class:`EpisodeFileError` unless ``path`` holds ``episodes`` plain episodes of ``total_steps`` steps.

    ``episodes`` and ``total_steps`` are ``metadata.json``'s counts. Nothing outside the
    file is read, no link is followed, and no array is read but the episodes'
    ``total_steps`` attributes.
    """
    _check_regular_file(path)
    try:
        with h5py.File(path, "r") as file:
            _check_episodes(file, episodes, total_steps, episode_layout(spaces), path.stat().st_size)
    except (OSError, RuntimeError) as error:  # h5py's errors of a broken file: bad input, not a bug
        raise EpisodeFileError(f"not a readable HDF5 file ({error})") from None


def episode_layout(spaces: Spaces) -> Layout:
    """The datasets Minari writes in an episode (paths in the episode's group) and their rows' shape (None: any)."""
    return {
        **_space_layout(spaces.observation, "observations", spaces.jpeg_encoding),
        **_space_layout(spaces.action, "actions", spaces.jpeg_encoding),
        **{member: () for member in STEP_MEMBERS if member != "actions"},
    }


def _check_regular_file(path: Path) -> None:
    """A regular file (a FIFO or a device would block or never end); ``OSError`` names a missing one."""
    if not stat.S_ISREG(os.stat(path).st_mode):
        raise EpisodeFileError("not a regular file: a dataset's episodes are an HDF5 file")


def _check_episodes(file: h5py.File, episodes: int, total_steps: int, layout: Layout, file_bytes: int) -> None:
    """Every episode's links, attributes and datasets; their steps add up to ``total_steps``."""
    if len(file) != episodes:
        raise EpisodeCountError(f"total_episodes is {episodes:,}, but the file holds {len(file):,} top-level entries")
    if episodes * (1 + len(layout)) > MAX_HDF5_LINKS:
        raise EpisodeFileError(f"{episodes:,} episodes of {len(layout)} datasets each: {_too_many_links()}")
    steps_seen = declared = links = 0
    for k in range(episodes):
        name = f"episode_{k}"
        episode = _episode_group(file, name)
        steps = _episode_steps(episode, name, total_steps - steps_seen)
        members = _hard_links(episode, name)
        links += 1 + len(members)
        if links > MAX_HDF5_LINKS:
            raise EpisodeFileError(f"{name}: {_too_many_links()}")
        declared += _check_members(episode, name, members, steps, layout)
        steps_seen += steps
    if steps_seen != total_steps:
        raise EpisodeCountError(f"total_steps is {total_steps:,}, but the file's episodes hold {steps_seen:,}")
    if declared > file_bytes:
        raise EpisodeFileError(f"its datasets declare {declared:,} bytes, more than the file's {file_bytes:,}")


def _too_many_links() -> str:
    """Words for a file beyond :data:`MAX_HDF5_LINKS`."""
    return f"more than the {MAX_HDF5_LINKS:,} links (groups and datasets) a dataset's file may hold"


def _episode_group(file: h5py.File, name: str) -> h5py.h5g.GroupID:
    """The group of episode ``name``, reached through a hard link of the file's root (checked before it is opened)."""
    key = name.encode()
    if not file.id.links.exists(key):
        raise EpisodeCountError(f"the file lacks {name}, which total_episodes counts")
    kind = file.id.links.get_info(key).type
    if kind != h5py.h5l.TYPE_HARD:
        raise EpisodeFileError(_link_problem(file.id, key, kind, name))
    group = h5py.h5o.open(file.id, key)
    if not isinstance(group, h5py.h5g.GroupID):
        raise EpisodeFileError(f"{name} is not a group")
    _check_single_name(group, name)
    return group


def _episode_steps(episode: h5py.h5g.GroupID, name: str, at_most: int) -> int:
    """The episode's ``total_steps`` attribute: an integer from 0 to ``at_most`` (the steps the metadata has left).

    Its attributes (Minari's and the episode's figures) are single values, at most
    :data:`MAX_EPISODE_ATTRIBUTES` of them.
    """
    attributes = h5py.h5o.get_info(episode).num_attrs
    if attributes > MAX_EPISODE_ATTRIBUTES:
        raise EpisodeFileError(f"{name} has {attributes:,} attributes, more than {MAX_EPISODE_ATTRIBUTES}")
    for index in range(attributes):
        attribute = h5py.h5a.open(episode, index=index)
        if attribute.shape != ():
            shown = _text(attribute.get_name())
            raise EpisodeFileError(f"{name}: attribute {shown!r} is not a single value (shape {attribute.shape})")
    if not h5py.h5a.exists(episode, b"total_steps"):
        raise EpisodeFileError(f"{name} has no total_steps attribute (its count of steps)")
    attribute = h5py.h5a.open(episode, b"total_steps")
    if attribute.dtype.kind not in "iu":
        raise EpisodeFileError(f"{name}: total_steps is not an integer")
    value = np.zeros((), attribute.dtype)
    attribute.read(value)
    if not 0 <= int(value) <= at_most:
        raise EpisodeFileError(f"{name}: total_steps {int(value):,} is not from 0 to the {at_most:,} steps left")
    return int(value)


def _hard_links(episode: h5py.h5g.GroupID, name: str) -> list[bytes]:
    """The names of every link under the episode, all hard links, at most :data:`MAX_LINKS_PER_EPISODE`."""
    walk = _LinkWalk(MAX_LINKS_PER_EPISODE)
    episode.links.visit(walk, info=True)
    if walk.other is not None:
        link, kind = walk.other
        raise EpisodeFileError(_link_problem(episode, link, kind, f"{name}/{_text(link)}"))
    if len(walk.names) > MAX_LINKS_PER_EPISODE:
        raise EpisodeFileError(f"{name} holds more than {MAX_LINKS_PER_EPISODE} groups and datasets")
    return walk.names


def _link_problem(group: h5py.h5g.GroupID, link: bytes, kind: int, where: str) -> str:
    """Words for a link that is not a hard link, with where it points (read from the link, never followed)."""
    described = _LINK_KINDS.get(kind, "a user-defined link")
    try:
        target = group.links.get_val(link)
    except (OSError, RuntimeError, ValueError):
        target = None
    if isinstance(target, tuple):
        target = ":".join(_text(part) for part in target)
    shown = f" to {_text(target)!r}" if isinstance(target, bytes | str) else ""
    return f"{where} is {described}{shown}: a dataset holds its episodes in its own file, as plain groups and datasets"


def _check_members(episode: h5py.h5g.GroupID, name: str, members: list[bytes], steps: int, layout: Layout) -> int:
    """Each group and dataset under the episode against the layout Minari writes; the bytes its datasets declare."""
    paths = [_text(member) for member in members]
    missing = [path for path in layout if path not in paths]
    if missing:
        raise EpisodeFileError(f"{name} lacks {missing[0]}")
    declared = 0
    for member, path in zip(members, paths, strict=True):
        rows = steps + 1 if path.split("/")[0] in STATE_MEMBERS else steps
        declared += _check_object(h5py.h5o.open(episode, member), f"{name}/{path}", path, rows, layout)
    return declared


def _check_object(item: h5py.h5o.ObjectID, where: str, path: str, rows: int, layout: Layout) -> int:
    """One group or dataset of an episode, where the layout has one; a dataset's declared bytes (0 for a group)."""
    _check_single_name(item, where)
    place = _place(path, layout)
    if isinstance(item, h5py.h5g.GroupID):
        if place not in ("group", "any"):
            raise EpisodeFileError(f"{where} is a group: {_PLACES[place]}")
        return 0
    if not isinstance(item, h5py.h5d.DatasetID):
        raise EpisodeFileError(f"{where} is neither a group nor a dataset")
    if place not in ("dataset", "any"):
        raise EpisodeFileError(f"{where} is a dataset: {_PLACES[place]}")
    _check_storage(item, where)
    return _check_shape(item, where, rows, layout.get(path))


_PLACES = {
    "dataset": "Minari writes a dataset there",
    "group": "Minari writes a group there",
    "": "no part of an episode as Minari writes it (the recorded spaces' arrays, rewards, flags and infos)",
}


def _place(path: str, layout: Layout) -> str:
    """What Minari writes at ``path`` of an episode: ``dataset``, ``group``, ``any`` (within infos) or ``""`` (none)."""
    if path in layout:
        return "dataset"
    if path == "infos" or any(leaf.startswith(f"{path}/") for leaf in layout):
        return "group"
    return "any" if path.startswith("infos/") else ""


def _check_single_name(item: h5py.h5o.ObjectID, where: str) -> None:
    """One hard link to the object: Minari never stores one object under two names (a loop, a shared group)."""
    names = h5py.h5o.get_info(item).rc
    if names != 1:
        raise EpisodeFileError(f"{where} has {names} names (hard links): each group and dataset has one")


def _check_storage(dataset: h5py.h5d.DatasetID, where: str) -> None:
    """The dataset's bytes are in this file, as they are: no external storage, no virtual mapping, no filter."""
    plist = dataset.get_create_plist()
    if plist.get_external_count():
        raise EpisodeFileError(f"{where} keeps its data in another file (external storage: {_external_files(plist)})")
    if plist.get_layout() == h5py.h5d.VIRTUAL:
        raise EpisodeFileError(f"{where} is a virtual dataset (its data mapped from other datasets)")
    if plist.get_nfilters():
        raise EpisodeFileError(f"{where} is compressed or filtered: this project's datasets store their arrays as is")


def _external_files(plist: h5py.h5p.PropDCID) -> str:
    """The first files an external storage names."""
    return ", ".join(repr(_text(plist.get_external(k)[0])) for k in range(min(plist.get_external_count(), 3)))


def _check_shape(dataset: h5py.h5d.DatasetID, where: str, rows: int, trailing: tuple[int, ...] | None) -> int:
    """``rows`` rows, the trailing shape of its space (if fixed), numbers; the bytes it declares."""
    shape = tuple(dataset.shape)
    if len(shape) == 0 or shape[0] != rows:
        raise EpisodeFileError(f"{where}: shape {shape}, but the episode's total_steps makes {rows:,} rows")
    if trailing is not None and shape[1:] != trailing:
        raise EpisodeFileError(f"{where}: shape {shape}, but its space makes rows of shape {trailing}")
    dtype = dataset.dtype
    base = h5py.check_vlen_dtype(dtype)
    if dtype.kind not in NUMERIC_KINDS and not (base is str or (base is not None and base.kind in NUMERIC_KINDS)):
        raise EpisodeFileError(f"{where}: elements of type {dtype}, not numbers")
    return math.prod(shape) * dtype.itemsize


def _space_layout(space: gym.Space, path: str, jpeg_encoding: bool) -> Layout:
    """The datasets Minari writes for ``space`` under ``path``, with their rows' shape (None: not fixed).

    A ``Dict`` is a group of its keys, a ``Tuple`` a group of ``_index_<i>``; an image
    Minari stores as JPEG bytes has rows of any length.
    """
    if isinstance(space, gym.spaces.Dict | gym.spaces.Tuple):
        keys = space.spaces.items() if isinstance(space, gym.spaces.Dict) else _tuple_keys(space)
        layout: Layout = {}
        for key, subspace in keys:
            layout.update(_space_layout(subspace, f"{path}/{key}", jpeg_encoding))
        return layout
    if (jpeg_encoding and is_image_space(space)) or space.shape is None:
        return {path: None}
    return {path: tuple(space.shape)}


def _tuple_keys(space: gym.spaces.Tuple) -> list[tuple[str, gym.Space]]:
    """A ``Tuple``'s spaces under the names Minari gives them."""
    return [(f"_index_{index}", subspace) for index, subspace in enumerate(space.spaces)]


def _text(name: bytes | str) -> str:
    """A name from the file as text (bytes that are not UTF-8 shown as escapes)."""
    return name.decode(errors="backslashreplace") if isinstance(name, bytes) else name
