"""The learners' refusals to train on the benchmark's evaluation seeds or split scenarios.

The splits' episodes use seeds from :data:`~training.data.generate.EVAL_SEED_BASE` (10^9)
and the published split scenarios (:func:`~training.evaluation.protocol.refuse_split_scenario`
knows their digests). Every learner's registry record names its refusal
(:attr:`training.learners.registry.Learner.refuse`), called with the run's options; the
command skips it only with ``--allow-evaluation-seeds`` (research on purpose):

- ``ppo``: env ``i``'s first episode uses seed ``--seed + i`` (the later ones come from
  the env's own generator): ``--seed .. --seed + envs - 1`` must stay below 10^9;
- ``dagger``: its own episodes use fixed seeds far below 10^9 (demonstrations from 0,
  learner episodes from 500,000), and ``--dataset`` is checked as for bc;
- ``bc``: the episodes it reads (the first ``--episodes``, or all) must have seeds below
  10^9, and the dataset's fixed scenario (if it was recorded on one) must not be a split's.

A refusal is an :class:`~training.data.generate.EvaluationSeedError` (bad input: exit 2).
"""

from __future__ import annotations

from typing import Any

from fetchcarry_env.errors import InputError
from training.data.generate import EVAL_SEED_BASE, EvaluationSeedError, check_training_seeds


def refuse_ppo(run: Any) -> None:
    """PPO's environments' first seeds."""
    check_training_seeds(run.options.seed, run.options.envs)


def refuse_dagger(run: Any) -> None:
    """DAgger's demonstration and learner seeds, and its ``--dataset``."""
    from training.learners.dagger import LEARNER_SEED_BASE

    check_training_seeds(0, run.options.demonstrations)
    check_training_seeds(LEARNER_SEED_BASE, run.options.iterations * run.options.episodes_per_iteration)
    if run.options.dataset is not None:
        refuse_dataset(run.options.dataset, run.options.demonstrations)


def refuse_bc(run: Any) -> None:
    """BC's dataset (the episodes it reads)."""
    refuse_dataset(run.dataset, run.episodes)


def refuse_dataset(dataset_id: str, episodes: int | None) -> None:
    """Refuse a dataset whose first ``episodes`` (None: all) reach the evaluation seeds or stand on a split scenario.

    A dataset that does not load is left to the learner, which says what is wrong with it.
    """
    from training.data.datasets import episode_metadata, load
    from training.evaluation.protocol import refuse_split_scenario

    try:
        dataset = load(dataset_id)
    except InputError:  # no such dataset, or a broken one: the learner's own reading says so
        return
    count = dataset.total_episodes if episodes is None else min(episodes, dataset.total_episodes)
    seeds = [int(episode_metadata(dataset, k)["seed"]) for k in range(count)]
    reached = [seed for seed in seeds if seed >= EVAL_SEED_BASE]
    if reached:
        raise EvaluationSeedError(
            f"dataset {dataset_id!r} holds {len(reached)} episodes of evaluation seeds (from {EVAL_SEED_BASE}, the "
            f"benchmark's splits; the first: {reached[0]}): training on them is refused (pass "
            "--allow-evaluation-seeds to use them on purpose)"
        )
    spec = dataset.spec.env_spec
    scenario = (spec.kwargs or {}).get("scenario") if spec is not None else None
    if isinstance(scenario, dict):
        refuse_split_scenario(scenario)
