"""The benchmark: learned policies against the MILP expert on fixed, versioned scenario lists.

```python
from training import benchmark

report = benchmark.run_benchmark(["expert", "random", "runs/bc-set"], split="iid", episodes=50, out="bench/iid")
report.rows          # one benchmark.Row per policy and split (success, cost ratio, SPL, score, ...)
```

The public facade of the benchmark: the names below, gathered from the modules that own
them: :mod:`~training.evaluation.splits` (the versioned splits and folders of scenario
files), :mod:`~training.resolve` (named policies, run folders, ``module:factory``),
:mod:`~training.evaluation.episodes` (one episode, one record),
:mod:`~training.evaluation.metrics` (cost ratio, SPL, the normalised score; Wilson
intervals from :mod:`training.stats`), :mod:`~training.evaluation.report` (``summary.md``),
:mod:`~training.pictures.benchmark` (the plots) and :mod:`~training.evaluation.runner`
(workers, incremental ``results.json``).
"""

from training.errors import BenchmarkError
from training.evaluation.metrics import Row, fill_expert_costs, spl, summarise, wilson
from training.evaluation.report import summary_markdown
from training.evaluation.runner import BenchmarkReport, run_benchmark
from training.evaluation.splits import (
    EVAL_SEED_BASE,
    SPLITS,
    EvalScenario,
    folder_scenarios,
    get_split,
    split_scenarios,
)
from training.pictures.benchmark import plot_demonstrations, plot_learning_curve, plot_splits
from training.resolve import FACTORIES, Factory, PolicySpec, available, resolve

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
