"""The benchmark: learned policies against the MILP expert on fixed, versioned scenario lists.

```python
from training import benchmark

report = benchmark.run_benchmark(["expert", "random", "runs/bc-set"], split="iid", episodes=50, out="bench/iid")
report.rows          # one benchmark.Row per policy and split (success, cost ratio, SPL, score, ...)
```

One module per concern: :mod:`~training.benchmark.splits` (the versioned splits and
folders of scenario files), :mod:`~training.benchmark.policies` (the registry of named
policies and run folders), :mod:`~training.benchmark.episodes` (one episode, one
record), :mod:`~training.benchmark.metrics` (Wilson intervals, cost ratio, SPL, the
normalised score), :mod:`~training.benchmark.report` (``summary.md`` and plots) and
:mod:`~training.benchmark.runner` (workers, incremental ``results.json``).
"""

from training.benchmark.errors import BenchmarkError
from training.benchmark.metrics import Row, fill_expert_costs, spl, summarise, wilson
from training.benchmark.policies import FACTORIES, Factory, PolicySpec, available, resolve
from training.benchmark.report import plot_demonstrations, plot_learning_curve, plot_splits, summary_markdown
from training.benchmark.runner import BenchmarkReport, run_benchmark
from training.benchmark.splits import EVAL_SEED_BASE, SPLITS, EvalScenario, folder_scenarios, get_split, split_scenarios

__all__ = [
    "EVAL_SEED_BASE",
    "FACTORIES",
    "SPLITS",
    "BenchmarkError",
    "BenchmarkReport",
    "EvalScenario",
    "Factory",
    "PolicySpec",
    "Row",
    "available",
    "fill_expert_costs",
    "folder_scenarios",
    "get_split",
    "plot_demonstrations",
    "plot_learning_curve",
    "plot_splits",
    "resolve",
    "run_benchmark",
    "spl",
    "split_scenarios",
    "summarise",
    "summary_markdown",
    "wilson",
]
