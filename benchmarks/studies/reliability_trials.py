"""The reliability trials of docs/reliability.md: ``PYTHONPATH=$PWD python benchmarks/studies/reliability_trials.py``.

Starts ``python -m training.cli generate`` in subprocesses (a fresh
``MINARI_DATASETS_PATH`` per try) and prints, as JSON: two runs on one dataset id at
once; SIGINT at a random moment (random policy with one worker, the expert with two
workers, the expert with one worker on ``multi``, where most time is in SCIP) and the
resume after it; the same for SIGTERM of ``--workers 2`` (exit 143, no leaked
semaphores); SIGKILL of the main process of ``--workers 2`` and how long its children
outlive it. Takes about seven minutes on two cores. Not part of the test suite (the
tests check the same, smaller, without timing anything).
"""

from __future__ import annotations

import json
import os
import random
import signal
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import h5py
import psutil

ROOT = Path(__file__).resolve().parents[2]
RNG = random.Random(0)


def cli(args: list[str], root: Path) -> subprocess.Popen:
    env = {**os.environ, "PYTHONPATH": str(ROOT), "MINARI_DATASETS_PATH": str(root)}
    command = [sys.executable, "-m", "training.cli", *args]
    return subprocess.Popen(command, env=env, stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def two_runs_on_one_id(pairs: int = 10) -> dict:
    counts = {"pairs": pairs, "one_0_one_2_busy": 0, "tracebacks": 0, "steps_mismatch": 0, "other": []}
    args = ["generate", "--family", "basic", "--policy", "random", "--episodes", "20", "--dataset-id", "trial/c-v0"]
    for _ in range(pairs):
        root = Path(tempfile.mkdtemp())
        first = cli([*args, "--no-progress"], root)
        time.sleep(RNG.uniform(0, 0.3))
        second = cli([*args, "--no-progress"], root)
        outputs = [p.communicate() for p in (first, second)]
        codes = sorted([first.returncode, second.returncode])
        counts["tracebacks"] += sum("Traceback" in err for _, err in outputs)
        if codes == [0, 2] and any("another run is working" in err for _, err in outputs):
            counts["one_0_one_2_busy"] += 1
        else:
            counts["other"].append(codes)
        metadata = json.loads((root / "trial/c-v0/data/metadata.json").read_text())
        with h5py.File(root / "trial/c-v0/data/main_data.hdf5") as file:
            stored = sum(len(file[e]["actions"]) for e in file)
        counts["steps_mismatch"] += metadata["total_steps"] != stored
    return counts


def interrupt(options: list[str], signum: int = signal.SIGINT, tries: int = 10) -> dict:
    """``signum`` to a running ``generate`` at a random moment, ``tries`` times; then the resume."""
    status = 128 + signum  # 130 after SIGINT, 143 after SIGTERM
    counts = {"tries": tries, f"exit_{status}": 0, "tracebacks": 0, "leaked_semaphores": 0, "hung": 0,
              "max_stop_s": 0.0, "resumed": 0}  # fmt: skip
    for _ in range(tries):
        root = Path(tempfile.mkdtemp())
        run = cli(["generate", *options, "--episodes", "100000", "--dataset-id", "trial/i-v0", "--no-progress"], root)
        time.sleep(RNG.uniform(1.0, 4.0))
        sent = time.monotonic()
        run.send_signal(signum)
        try:
            _, err = run.communicate(timeout=30)
        except subprocess.TimeoutExpired:
            counts["hung"] += 1
            run.kill()
            _, err = run.communicate()
        counts["max_stop_s"] = round(max(counts["max_stop_s"], time.monotonic() - sent), 2)
        counts[f"exit_{status}"] += run.returncode == status
        counts["tracebacks"] += "Traceback" in err or "Exception ignored" in err
        counts["leaked_semaphores"] += "leaked semaphore" in err
        staged = len(list((root / ".staging/trial/i-v0").glob("episode_*.npz")))
        again = cli(["generate", *options, "--episodes", str(staged + 2), "--dataset-id", "trial/i-v0"], root)
        out, _ = again.communicate(timeout=600)
        counts["resumed"] += again.returncode == 0 and f"({staged} resumed" in out
    return counts


def sigkill(tries: int = 5) -> dict:
    counts: dict = {"tries": tries, "children": [], "all_gone_after_s": []}
    for _ in range(tries):
        root = Path(tempfile.mkdtemp())
        args = ["generate", "--family", "push", "--workers", "2", "--episodes", "100000", "--dataset-id", "trial/k-v0"]
        run = cli([*args, "--no-progress"], root)
        parent = psutil.Process(run.pid)
        time.sleep(RNG.uniform(2.0, 4.0))
        children = parent.children(recursive=True)
        run.kill()
        run.wait()
        killed = time.monotonic()
        _, alive = psutil.wait_procs(children, timeout=30)
        counts["children"].append(len(children))
        counts["all_gone_after_s"].append(None if alive else round(time.monotonic() - killed, 2))
        for child in alive:
            child.kill()
    return counts


def main() -> None:
    results = {
        "two_runs_on_one_id": two_runs_on_one_id(),
        "sigint_random_1_worker": interrupt(["--family", "basic", "--policy", "random"]),
        "sigint_expert_2_workers": interrupt(["--family", "push", "--workers", "2"]),
        "sigint_expert_1_worker_multi": interrupt(["--family", "multi"]),
        "sigterm_expert_2_workers": interrupt(["--family", "push", "--workers", "2"], signal.SIGTERM),
        "sigkill_2_workers": sigkill(),
    }
    print(json.dumps(results, indent=1))


if __name__ == "__main__":
    main()
