"""The story notebooks still run against the current API (they are built from notebooks/build.py)."""

from __future__ import annotations

import importlib.util
from pathlib import Path

import pytest
from nbclient import NotebookClient
from nbformat.v4 import new_notebook

NOTEBOOKS_DIR = Path(__file__).resolve().parent.parent / "notebooks"
spec = importlib.util.spec_from_file_location("notebook_build", NOTEBOOKS_DIR / "build.py")
build = importlib.util.module_from_spec(spec)
spec.loader.exec_module(build)


@pytest.mark.parametrize("name", sorted(build.NOTEBOOKS))
def test_notebook_executes(name, tmp_path, monkeypatch):
    monkeypatch.setenv("MINARI_DATASETS_PATH", str(tmp_path))
    before = sorted(NOTEBOOKS_DIR.iterdir())
    notebook = new_notebook(cells=build.NOTEBOOKS[name])
    notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
    NotebookClient(notebook, timeout=300, resources={"metadata": {"path": str(NOTEBOOKS_DIR)}}).execute()
    errors = [o for c in notebook.cells for o in c.get("outputs", []) if o.get("output_type") == "error"]
    assert errors == []
    assert sorted(NOTEBOOKS_DIR.iterdir()) == before  # a notebook leaves no file behind (02 left plan.png)
