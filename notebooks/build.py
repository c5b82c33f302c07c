"""Write and execute the story notebooks: ``python notebooks/build.py``.

The notebooks are short stories for people; their source lives here so that a change
of API shows up as a failing execution, not as a silently stale notebook. Each is
executed with nbclient and saved with its outputs.
"""

from __future__ import annotations

import sys
from pathlib import Path

import nbformat
from nbclient import NotebookClient
from nbformat.v4 import new_code_cell, new_markdown_cell, new_notebook

from training.evaluation.splits import get_split

HERE = Path(__file__).resolve().parent

QUICKSTART = [
    new_markdown_cell(
        "# fetchcarry in five minutes\n\n"
        "A Toyota-HSR-like robot must carry a bottle from one table to a goal on another. On the goal "
        "stands a block that has to be **pushed aside** first, and the block's neighbours rule out some "
        "push directions (the paper's Fig. 3). One action of `FetchCarryPush-v0` is one *phase* of the "
        "paper's task-and-motion plan: where the base goes, its heading, the arm posture, and what the "
        "arm does there."
    ),
    new_code_cell(
        "import gymnasium as gym\n"
        "import matplotlib.pyplot as plt\n\n"
        "import fetchcarry_env  # registers FetchCarryPush-v0\n"
        "from fetchcarry_env.drawing import render_rgb\n\n"
        'env = gym.make("FetchCarryPush-v0", family="push", render_mode="rgb_array")\n'
        "obs, info = env.reset(seed=7)\n"
        "scenario = env.unwrapped.scenario\n"
        "print(scenario.name, '|', len(scenario.clutter), 'pieces of clutter |', env.action_space)\n"
        "plt.figure(figsize=(6, 6)); plt.imshow(render_rgb(scenario, env.unwrapped.state)); plt.axis('off');"
    ),
    new_markdown_cell(
        "The action is `MultiDiscrete([nx, ny, heading, posture, mode])` over a 5 cm lattice. "
        "`action_masks()` rules out what can never work (cells where the base does not fit, pick with a "
        "full hand, place with an empty one), in sb3-contrib's MaskablePPO convention. The observation is "
        "a goal-env `Dict` that holds the whole geometry, so a planner can rebuild the scenario from it."
    ),
    new_code_cell(
        "mask = env.unwrapped.action_masks()\n"
        "print('mask length', mask.shape[0], '| allowed modes now:', mask[-4:])\n"
        "print({k: v.shape for k, v in obs.items()})"
    ),
    new_markdown_cell(
        "## The MILP expert acts\n\n"
        "`ExpertPolicy` follows stable-baselines3's `predict` protocol. It decodes the observation, solves "
        "the paper's MILP on SCIP, and replays the plan one phase per step, replanning if physics departs "
        "from it."
    ),
    new_code_cell(
        "from expert import ExpertPolicy\n\n"
        "policy = ExpertPolicy(env)\n"
        "frames = [env.render()]\n"
        "while True:\n"
        "    action, _ = policy.predict(obs, deterministic=True)\n"
        "    obs, reward, terminated, truncated, info = env.step(action)\n"
        "    frames.append(env.render())\n"
        "    print(f\"reward {reward:7.2f}  delivered {info['delivered']}  invalid {info['invalid_action']}\")\n"
        "    if terminated or truncated:\n"
        "        break\n"
        "print('success:', info['is_success'], '| path', round(info['path_length'], 2), 'm |', policy.stats)"
    ),
    new_code_cell(
        "fig, axes = plt.subplots(1, len(frames), figsize=(3 * len(frames), 3))\n"
        "for k, (ax, frame) in enumerate(zip(axes, frames)):\n"
        "    ax.imshow(frame); ax.set_title('start' if k == 0 else f'phase {k}'); ax.axis('off')\n"
        "env.close()"
    ),
]

PLANNER = [
    new_markdown_cell(
        "# The planner: the paper's MILP on SCIP\n\n"
        "`plan(scenario)` builds the whole formulation of the paper (Eq. 1-27: motion, grasp logic, "
        "postures, collision regions, push-aside, area bounds) for a growing number of phases and returns "
        "the optimal `Plan`. `docs/formulation.md` maps every equation to its code."
    ),
    new_code_cell(
        "from IPython.display import Image\n\n"
        "from expert import plan, validate_plan\n"
        "from expert.plot import plot_plan\n"
        "from fetchcarry_env import Scenario\n\n"
        'scenario = Scenario.load("../examples/push_basic.json")\n'
        "result = plan(scenario, time_limit=10.0)\n"
        "print(result.status, 'objective', round(result.objective, 3), '|', result.stats['total_s'], 's')\n"
        "for k, phase in enumerate(result.phases):\n"
        "    print(k, phase.action.ljust(5), phase.base, phase.heading, phase.target, phase.posture)\n"
        "print('violations:', validate_plan(scenario, result))"
    ),
    new_code_cell(
        "import tempfile\n"
        "from pathlib import Path\n\n"
        "picture = Path(tempfile.mkdtemp()) / 'plan.png'  # not into the notebooks folder\n"
        "plot_plan(scenario, result, picture)\n"
        "Image(str(picture))"
    ),
    new_markdown_cell(
        "## How fast, on every family\n\n"
        "Times are the whole call, model building included, in this process (importing pyscipopt "
        "alone costs 0.15 s per process). `python -m benchmarks planner` reproduces the paper's Section V."
    ),
    new_code_cell(
        "import numpy as np\n"
        "from fetchcarry_env.families import get_family\n\n"
        "for name in ['basic', 'push', 'corridor', 'multi-2', 'multi-3']:\n"
        "    times = []\n"
        "    for seed in range(5):\n"
        "        s = get_family(name).sample(np.random.default_rng(seed))\n"
        "        r = plan(s, time_limit=10.0)\n"
        "        times.append(r.stats['total_s'])\n"
        "        assert r.status == 'optimal' and validate_plan(s, r) == []\n"
        "    print(f'{name:9s} median {1000 * np.median(times):6.1f} ms   max {1000 * max(times):6.1f} ms')"
    ),
]

DATASET = [
    new_markdown_cell(
        "# Expert demonstrations as a Minari dataset\n\n"
        "`fetchcarry generate` runs the expert on seeded scenarios and writes a Minari dataset. Each "
        "episode keeps its scenario and seed, so it replays exactly; an interrupted run resumes."
    ),
    new_code_cell(
        "import os, subprocess, tempfile\n\n"
        "os.environ['MINARI_DATASETS_PATH'] = tempfile.mkdtemp()\n"
        "cmd = ['fetchcarry', 'generate', '--family', 'push', '--episodes', '4', '--workers', '1',\n"
        "       '--dataset-id', 'fetchcarry/push-expert-v0', '--no-progress']\n"
        "print(subprocess.run(cmd, capture_output=True, text=True).stdout)"
    ),
    new_code_cell(
        "import minari\n\n"
        "dataset = minari.load_dataset('fetchcarry/push-expert-v0')\n"
        "print(dataset.total_episodes, 'episodes,', dataset.total_steps, 'steps')\n"
        "episode = next(dataset.iterate_episodes())\n"
        "print('actions of episode 0:\\n', episode.actions)\n"
        "print('rewards:', episode.rewards.round(2))"
    ),
    new_code_cell(
        "print(subprocess.run(['fetchcarry', 'dataset', 'replay', 'fetchcarry/push-expert-v0', '--episode', '0'],\n"
        "                     capture_output=True, text=True).stdout)"
    ),
]

SPLITS_SHOWN = ("iid", "more-objects", "layouts", "push-required", "objects", "apartment", "perturbed")


def split_lines(names: tuple[str, ...] = SPLITS_SHOWN) -> str:
    """One markdown line per split: its name, the version and part it means now, and its description."""
    return "\n".join(f"- `{name}` (`{get_split(name).name}`): {get_split(name).description}" for name in names)


BENCHMARK = [
    new_markdown_cell(
        "# Benchmark learned policies against the MILP expert\n\n"
        "`fetchcarry benchmark` (or `training.benchmark.run_benchmark`) runs every policy on the same fixed, "
        "versioned scenarios and compares it with the expert's reference scenario by scenario. A split's name "
        "without a version means its newest version's test part:\n\n"
        f"{split_lines()}\n\n"
        "Each episode's cost is its task cost (travel, plus 10 for every object not yet at its goal after each "
        "step, plus penalties), minus its return; the reference is the expert's proven optimum of it. The older "
        "versions (`iid-v1`, `layouts-v2`, ...) were referenced under release 0.2's task, and the benchmark "
        "refuses to score them; `layouts-v0` and `layouts-v1` are the training families' rooms and corridors "
        "turned a quarter turn. Evaluation seeds start at 10^9, far from any training seed. Here: a tiny budget, "
        "so the intervals are wide."
    ),
    new_code_cell(
        "import importlib.util\n"
        "import tempfile\n"
        "from pathlib import Path\n\n"
        "from training import benchmark\n\n"
        "work = Path(tempfile.mkdtemp(prefix='fetchcarry-benchmark-'))\n"
        "policies = ['expert', 'random', 'random-phases']\n"
        "if importlib.util.find_spec('training.learners.bc') is not None:  # a tiny BC run, if BC is installed\n"
        "    from fetchcarry_env.observation import Capacity\n"
        "    from training.learners.bc import BCConfig, record_demonstrations, train_bc\n\n"
        "    demonstrations = record_demonstrations('basic', range(20))\n"
        "    train_bc(demonstrations, BCConfig(epochs=30, hidden=64), Capacity(), out=work / 'bc-basic')\n"
        "    policies.append(str(work / 'bc-basic'))\n"
        "report = benchmark.run_benchmark(policies, split='iid', episodes=4, out=work / 'iid')\n"
        "print(len(report.records), 'episodes in', work / 'iid' / 'results.json')\n"
        "report.records[0]"
    ),
    new_markdown_cell(
        "`summary.md` holds the table: success with a 95 % Wilson interval, cost ratio to the reference on the "
        "same scenarios (episodes both solved), an SPL-style cost-weighted success, phases and pushes next to "
        "the reference's, invalid actions and contacts, the time per decision next to the planner's, and the "
        "score: 0 for doing nothing (every object waiting all 50 phases, a return of -500 per object), 100 for "
        "the reference (the expert's proven optimum shipped with a published split, else this run's expert), "
        "linear in the episode returns (minus the task cost) in between, and a failed episode never above a "
        "successful one on the same scenario: 100 x sum(R - F) / sum(R_reference - F)."
    ),
    new_code_cell(
        "from IPython.display import Image, Markdown, display\n\n"
        "display(Markdown((work / 'iid' / 'summary.md').read_text()))\n"
        "Image(str(work / 'iid' / 'splits.png'))"
    ),
    new_markdown_cell(
        "A run folder's `metrics.csv` draws as learning curves; `plot_demonstrations` draws success against "
        "the number of expert demonstrations from records that carry a `demonstrations` count."
    ),
    new_code_cell(
        "if (work / 'bc-basic').exists():\n"
        "    display(Image(str(benchmark.plot_learning_curve(work / 'bc-basic', work / 'curve.png'))))"
    ),
]

NOTEBOOKS = {
    "01_quickstart.ipynb": QUICKSTART,
    "02_planner.ipynb": PLANNER,
    "03_dataset.ipynb": DATASET,
    "04_benchmark.ipynb": BENCHMARK,
}


def build(names: list[str]) -> None:
    for name in names or NOTEBOOKS:
        notebook = new_notebook(cells=NOTEBOOKS[name])
        notebook.metadata["kernelspec"] = {"name": "python3", "display_name": "Python 3", "language": "python"}
        NotebookClient(notebook, timeout=300, resources={"metadata": {"path": str(HERE)}}).execute()
        nbformat.write(notebook, HERE / name)
        print(f"wrote {HERE / name}")


if __name__ == "__main__":
    build(sys.argv[1:])
