"""The settings of a BC and a PPO run: plain dataclasses, light to import (the command line shows their defaults).

Every field is saved in a run folder's ``config.json``; the defaults are the budgets a
published table uses.
"""

from __future__ import annotations

from dataclasses import dataclass

HELDOUT_SEED_BASE = 100_000  # held-out episode k uses HELDOUT_SEED_BASE + k (the learning checks' held-out seeds)


@dataclass(frozen=True)
class BCConfig:
    """What a BC run trains (every field is saved in the run folder's ``config.json``)."""

    encoder: str = "mlp"  # "mlp" or "set"
    hidden: int = 256  # units per hidden layer (mlp) or token width (set)
    epochs: int = 60
    batch_size: int = 128
    learning_rate: float = 1e-3
    weight_decay: float = 1e-5
    seed: int = 0
    relative: bool = True  # append positions relative to the base (mlp: and clutter relative to goals; set: per token)
    push_scores: bool = False  # mlp: add scores from whether each push leaves a goal covered (PushScores)
    avoid_repeats: bool = True  # acting: in a state met before this episode, not the candidates chosen there
    avoid_returns: bool = False  # acting: no approach or waypoint move seen this episode to end in a state met before
    push_after_approach: bool = False  # acting: no approach right after an approach (the expert's data never has one)

    def __post_init__(self) -> None:
        if self.encoder not in ("mlp", "set"):
            raise ValueError(f"encoder must be 'mlp' or 'set', got {self.encoder!r}")
        if min(self.hidden, self.epochs, self.batch_size) < 1 or self.learning_rate <= 0:
            raise ValueError("hidden, epochs and batch_size must be positive, learning_rate > 0")


@dataclass(frozen=True)
class PPOOptions:
    """A PPO run's budget and settings (the defaults are the published budget)."""

    steps: int = 20_000  # env steps in total
    n_steps: int = 256  # env steps per rollout
    batch_size: int = 64
    n_epochs: int = 10
    learning_rate: float = 3e-4
    gamma: float = 0.99
    checkpoint_every: int = 1024  # env steps between checkpoints
    encoder: str = "mlp"  # the actor's network ("mlp" or "set"; with init, the init run's)
    hidden: int = 256
    seed: int = 0
    init: str | None = None  # a bc or dagger run folder whose network starts the actor

    def __post_init__(self) -> None:
        if min(self.steps, self.n_steps, self.batch_size, self.n_epochs, self.checkpoint_every) < 1:
            raise ValueError("steps, n_steps, batch_size, n_epochs and checkpoint_every must be positive")
        if self.learning_rate <= 0 or not 0 < self.gamma <= 1:
            raise ValueError("learning_rate must be positive and gamma in (0, 1]")
        BCConfig(encoder=self.encoder, hidden=self.hidden)


@dataclass(frozen=True)
class DaggerOptions:
    """A DAgger run's budget (the defaults are the published budget)."""

    demonstrations: int = 100  # expert episodes of iteration 0
    iterations: int = 4  # learner iterations after iteration 0
    episodes_per_iteration: int = 50  # learner episodes labelled per iteration
    eval_episodes: int = 50  # held-out episodes measured after each iteration
    time_limit: float = 10.0  # seconds per planning call of the expert
    epochs: int = 40  # epochs of each retraining
    nearest_moves: bool = False  # label an expert move no candidate expresses with the nearest allowed move
    learner_families: tuple[str, ...] = ()  # learner episode k draws from the k-th (cycled); () = the run's family
    dataset: str | None = None  # iteration 0: the first `demonstrations` episodes of this phases dataset, not new ones

    def __post_init__(self) -> None:
        object.__setattr__(self, "learner_families", tuple(self.learner_families))  # a list from config.json too
        if min(self.demonstrations, self.iterations, self.episodes_per_iteration, self.eval_episodes, self.epochs) < 1:
            raise ValueError("demonstrations, iterations, episodes per iteration, eval episodes, epochs must be >= 1")
        if self.time_limit <= 0:
            raise ValueError(f"the time limit must be positive, got {self.time_limit}")
