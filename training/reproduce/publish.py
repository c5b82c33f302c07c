"""Where a reproduction came from (its commits) and what of it goes into the repository (under 50 MB).

:func:`record_commit` appends the code's commit to ``DIR/reproduce.json`` at every call,
so that the summary can say whether the whole table was made at one commit
(:func:`commit_line`); a folder continued across commits says so, and names them.

:func:`publish` copies what a paper's reader needs to check the table into a folder of
the repository: ``summary.md``, every record (``results.json.gz``: the table's
``results.json``, gzip-compressed, which the readers take as it is), the plots, each
run's ``config.json`` and ``metrics.csv``, and the weights (``model.pt``) of the best
run of each learned baseline of the table (the seed with the highest success on the
``iid`` test part; not the demonstrations curve's smaller BC runs), and refuses
(:class:`PublishError`) when the copy would exceed :data:`MAX_PUBLISHED_BYTES`.
"""

from __future__ import annotations

import json
import shutil
import subprocess
from collections.abc import Sequence
from pathlib import Path
from typing import Any

from fetchcarry_env.errors import InputError
from fetchcarry_env.jsontext import JsonInputError, read_json
from training.evaluation.compare import method_of
from training.evaluation.results import RESULTS, RESULTS_GZIP, encode_results, read_results
from training.files import write_atomically
from training.reproduce.table import on_curve_only

MAX_PUBLISHED_BYTES = 50 * 2**20  # what the repository holds of a reproduction
SETTINGS_FILE = "reproduce.json"
RUN_FILES = ("config.json", "metrics.csv")  # of every run; model.pt only for the best run of each baseline
TABLE_FILES = ("summary.md", "timings.json", SETTINGS_FILE, "splits.png", "objects.png", "ppo_curves.png",
               "demonstrations.png")  # fmt: skip
REPOSITORY = Path(__file__).resolve().parents[2]


class PublishError(InputError):
    """A reproduction that cannot be published (not finished, or too large for the repository)."""


def current_commit(repository: Path = REPOSITORY) -> str:
    """The checked-out commit (40 hex digits, ``+dirty`` with uncommitted changes to tracked files), or ``unknown``."""
    try:
        head = subprocess.run(["git", "-C", str(repository), "rev-parse", "HEAD"], capture_output=True, text=True,
                              timeout=30, check=True).stdout.strip()  # fmt: skip
        status = subprocess.run(["git", "-C", str(repository), "status", "--porcelain", "--untracked-files=no"],
                                capture_output=True, text=True, timeout=30, check=True).stdout  # fmt: skip
    except (OSError, subprocess.SubprocessError):
        return "unknown"
    return head + ("+dirty" if status.strip() else "")


def record_commit(out: Path, commit: str | None = None) -> list[str]:
    """Append this call's commit to ``out/reproduce.json``'s ``commits`` (once each, in order); the list."""
    file = out / SETTINGS_FILE
    try:
        settings = read_json(file, 10_000_000)
    except (FileNotFoundError, JsonInputError):
        settings = {}
    settings = settings if isinstance(settings, dict) else {}
    commits = [c for c in settings.get("commits", []) if isinstance(c, str)]
    commit = commit or current_commit()
    if commit not in commits:
        commits.append(commit)
    file.write_text(json.dumps({**settings, "commits": commits}, indent=2) + "\n")
    return commits


def commit_line(commits: Sequence[str]) -> str:
    """The summary's sentence on provenance: one commit, several, or none known."""
    if len(commits) == 1 and commits[0] != "unknown" and not commits[0].endswith("+dirty"):
        return f"Made by one `fetchcarry reproduce` call at commit `{commits[0]}`."
    if len(commits) == 1:
        return f"Made at `{commits[0]}`: not a clean commit, so the code is not pinned."
    listed = ", ".join(f"`{c}`" for c in commits)
    return f"Made across {len(commits)} commits ({listed}): continued after the code changed, so not one commit."


def best_runs(records: Sequence[dict[str, Any]]) -> dict[str, str]:
    """Per learned baseline of the table, its run with the highest success on the iid test part (ties: lower seed)."""
    scores: dict[str, dict[str, list[bool]]] = {}
    for r in records:
        method, seed = method_of(r)
        if seed is not None and r["split"].startswith("iid") and not on_curve_only(method):
            scores.setdefault(method, {}).setdefault(r["policy"], []).append(r["success"])
    return {m: max(runs, key=lambda run: (sum(runs[run]) / len(runs[run]), -len(run), run[::-1]))
            for m, runs in scores.items()}  # fmt: skip


def publish(out: str | Path, dest: str | Path) -> dict[str, Any]:
    """Copy the publishable part of the reproduction ``out`` into ``dest``; what was copied and its size."""
    out, dest = Path(out), Path(dest)
    if not (out / "summary.md").is_file():
        raise PublishError(f"{out} holds no finished table (no summary.md): run fetchcarry reproduce first")
    records = read_results(out / RESULTS)
    files = [out / name for name in TABLE_FILES if (out / name).is_file()]
    runs = sorted(p for p in (out / "runs").iterdir() if p.is_dir()) if (out / "runs").is_dir() else []
    files += [run / name for run in runs for name in RUN_FILES if (run / name).is_file()]
    weights = [out / "runs" / name / "model.pt" for name in best_runs(records).values()]
    files += [w for w in weights if w.is_file()]
    compressed = encode_results(records, compressed=True)
    size = sum(f.stat().st_size for f in files) + len(compressed)
    if size > MAX_PUBLISHED_BYTES:
        raise PublishError(f"publishing {out} takes {size / 2**20:.1f} MB, above {MAX_PUBLISHED_BYTES // 2**20} MB")
    dest.mkdir(parents=True, exist_ok=True)
    for file in files:
        target = dest / file.relative_to(out)
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copy2(file, target)
    write_atomically(dest / RESULTS_GZIP, compressed)
    return {"files": len(files) + 1, "bytes": size, "weights": [str(w.relative_to(out)) for w in weights]}
