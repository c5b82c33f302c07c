"""Run folders that ship with the repository, each with a card: ``--policies NAME@published`` loads one.

Each folder ``training/published/NAME/`` is a finished run of ``fetchcarry train`` (its
``config.json``, ``model.pt`` and ``metrics.csv``; not its ``checkpoint.pt``, which only
resumes training) and ``card.md``: the data it learned from, the recipe, the training
seed, its scores, and the commands that made it and that reproduce its records
(``fetchcarry benchmark --check RESULTS --policies NAME@published``). The benchmark labels
its episodes ``NAME``, as it labels any run folder by its name.
"""

from __future__ import annotations

from pathlib import Path

SUFFIX = "@published"  # what marks a published run's name on the command line
FOLDER = Path(__file__).parent


def published_names() -> list[str]:
    """The names of the published runs, sorted."""
    return sorted(p.name for p in FOLDER.iterdir() if (p / "config.json").is_file())


def published_run(name: str) -> Path:
    """The folder of the published run ``name`` (with or without :data:`SUFFIX`); ``KeyError`` naming the known ones."""
    bare = name.removesuffix(SUFFIX)
    if bare not in published_names():
        raise KeyError(f"no published run {bare!r}; published: {', '.join(published_names()) or 'none'}")
    return FOLDER / bare
