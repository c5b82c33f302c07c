"""The budgets of the published table: how much ``fetchcarry reproduce`` records, trains and evaluates.

Two budgets: ``full`` (the published table; 2 h 42 min measured for three training seeds
on a shared 2-core machine with two workers, 12,491 CPU s: docs/benchmarks/learning.md,
"Its time") and ``smoke``
(every stage at a toy size: 145 s measured at load 2-6 on 2 cores; what the tests run). Every field is
saved in ``DIR/reproduce.json``, so a folder is never continued with another budget. A
budget with counts out of range raises :class:`~fetchcarry_env.errors.InputError`.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

from fetchcarry_env.errors import InputError
from training.learners.options import BCConfig, DaggerOptions, PPOOptions, read_capacity

TRAINING_FAMILY = "training"  # basic, push, corridor or multi-2, uniformly: the iid split's families
FIRST_SPLITS = ("iid", "more-objects", "layouts", "push-required")  # the table's splits before the graded worlds
# The graded worlds too: k = 1..12 objects, a procedural apartment, iid scenarios perturbed (docs/families.md)
TABLE_SPLITS = (*FIRST_SPLITS, "objects", "apartment", "perturbed")
TABLE_CAPACITY = "objects=12,clutter=12"  # holds every scenario of TABLE_SPLITS: every learner (flat ones too) acts
# DaggerOptions' field -> the Budget field it is taken from
DAGGER_FIELDS = {
    "demonstrations": "dagger_demonstrations",
    "iterations": "dagger_iterations",
    "episodes_per_iteration": "dagger_episodes",
    "eval_episodes": "dagger_eval",
    "time_limit": "time_limit",
    "epochs": "dagger_epochs",
}


@dataclass(frozen=True)
class Budget:
    """What one reproduction records, trains and evaluates (per training seed where it says so)."""

    name: str
    demonstrations: int  # expert episodes of the training dataset (seeds 0 .. demonstrations - 1)
    curve: tuple[int, ...]  # BC (flat MLP) on the dataset's first N episodes too: the demonstrations plot
    bc_epochs: int  # epochs of BC with the flat MLP (per run)
    set_epochs: int  # epochs of BC with the set encoder (slower per epoch)
    dagger_demonstrations: int  # DAgger's expert episodes before its first iteration
    dagger_iterations: int
    dagger_episodes: int  # learner episodes labelled by the expert per iteration
    dagger_epochs: int  # epochs of each retraining
    dagger_eval: int  # held-out episodes measured after each iteration (its metrics.csv)
    ppo_steps: int  # env steps of each PPO run (rounded up to whole rollouts)
    ppo_rollout: int  # env steps per rollout
    ppo_batch: int  # PPO minibatch size
    episodes: int  # benchmark episodes per split (every policy on the same scenarios)
    time_limit: float = 10.0  # seconds per planning call of the expert (datasets and DAgger's labels)
    aimed_iterations: int = 0  # dagger-aimed: BC on the whole dataset, then this many DAgger iterations; 0: none
    aimed_families: tuple[str, ...] = ("push", "multi-2")  # dagger-aimed's learner episodes draw from these in turn
    ppo_eval_every: int = 5120  # env steps between PPO's held-out evaluations (its curve of held-out success)
    ppo_eval: int = 50  # held-out episodes of each of those evaluations
    splits: tuple[str, ...] = FIRST_SPLITS  # the benchmark's splits (the newest version of each, its test part)
    capacity: str | None = None  # the observation's room (--capacity) of the dataset and every run; None: the env's

    def __post_init__(self) -> None:
        counts = (self.demonstrations, self.bc_epochs, self.set_epochs, self.ppo_steps, self.episodes)
        if min(counts) < 1 or any(n < 1 or n > self.demonstrations for n in self.curve):
            raise InputError("a budget's counts must be positive and its curve within its demonstrations")
        if not self.splits or len(set(self.splits)) < len(self.splits):
            raise InputError(f"a budget's splits must be distinct and at least one, got {self.splits}")
        if self.capacity is not None:
            object.__setattr__(self, "capacity", read_capacity(self.capacity))  # every count, as run folders save it
        if self.aimed_iterations < 0:
            raise InputError(f"aimed_iterations must be >= 0, got {self.aimed_iterations}")
        self.dagger_options()  # their own checks
        if self.aimed_iterations:
            self.aimed_options("dataset")
        self.ppo_options(0)

    def bc_config(self, encoder: str, seed: int) -> BCConfig:
        """The BC network of ``encoder`` for training seed ``seed``."""
        epochs = self.set_epochs if encoder == "set" else self.bc_epochs
        return BCConfig(encoder=encoder, epochs=epochs, seed=seed)

    def dagger_options(self) -> DaggerOptions:
        """The DAgger run of the table: the budget's fields named in :data:`DAGGER_FIELDS`, the rest defaulted."""
        fields = {option: getattr(self, field) for option, field in DAGGER_FIELDS.items()}
        return DaggerOptions(**fields, capacity=self.capacity)

    def aimed_options(self, dataset: str) -> DaggerOptions:
        """dagger-aimed: iteration 0 is BC on all of ``dataset`` (the flat MLP's epochs: the same network as
        ``bc-mlp`` of the seed), then ``aimed_iterations`` iterations of learner episodes from ``aimed_families``."""
        return replace(
            self.dagger_options(),
            demonstrations=self.demonstrations,
            iterations=self.aimed_iterations,
            epochs=self.bc_epochs,
            learner_families=self.aimed_families,
            dataset=dataset,
        )

    def ppo_options(self, seed: int, init: str | None = None) -> PPOOptions:
        return PPOOptions(
            steps=self.ppo_steps,
            n_steps=self.ppo_rollout,
            batch_size=self.ppo_batch,
            checkpoint_every=self.ppo_rollout * 4,
            seed=seed,
            init=init,
            eval_every=self.ppo_eval_every,
            eval_episodes=self.ppo_eval,
            capacity=self.capacity,
        )


FULL = Budget(
    name="full",
    demonstrations=1000,
    curve=(10, 30, 100, 300),
    bc_epochs=60,
    set_epochs=60,
    dagger_demonstrations=100,
    dagger_iterations=4,
    dagger_episodes=50,
    dagger_epochs=40,
    dagger_eval=20,
    ppo_steps=50_000,
    ppo_rollout=256,
    ppo_batch=64,
    episodes=300,  # the test part of every split: docs/protocol.md's minimum for a published table
    aimed_iterations=3,
    splits=TABLE_SPLITS,
    capacity=TABLE_CAPACITY,
)
SMOKE = Budget(
    name="smoke",
    demonstrations=6,
    curve=(2,),
    bc_epochs=2,
    set_epochs=1,
    dagger_demonstrations=2,
    dagger_iterations=1,
    dagger_episodes=2,
    dagger_epochs=2,
    dagger_eval=2,
    ppo_steps=32,
    ppo_rollout=32,
    ppo_batch=32,
    episodes=2,
    aimed_iterations=1,
    ppo_eval_every=32,
    ppo_eval=2,
    splits=TABLE_SPLITS,
    capacity=TABLE_CAPACITY,
)
BUDGETS = {budget.name: budget for budget in (FULL, SMOKE)}
