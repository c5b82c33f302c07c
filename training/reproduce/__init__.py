"""The published table in one command (``fetchcarry reproduce``): expert data, every baseline, every split.

:mod:`~training.reproduce.budgets` (what ``full`` and ``smoke`` train and evaluate),
:mod:`~training.reproduce.table` (the table's splits, references, baselines and run names),
:mod:`~training.reproduce.jobs` (training runs, up to W at a time),
:mod:`~training.reproduce.pipeline` (the stages, each skipped when complete) and
:mod:`~training.reproduce.aggregate` (``summary.md``, ``results.json`` and plots over
training seeds).

```python
from training.reproduce import SMOKE, reproduce

reproduce("published-smoke", seeds=1, budget=SMOKE, workers=2)
```
"""

from training.reproduce.budgets import BUDGETS, FULL, SMOKE, Budget
from training.reproduce.pipeline import reproduce

__all__ = ["BUDGETS", "FULL", "SMOKE", "Budget", "reproduce"]
