"""The settings of every learner's run: plain dataclasses, light to import (the command line is made from them).

Every field is saved in a run folder's ``config.json``; the defaults are the budgets a
published table uses. A field made with :func:`option` (a help text and how its values
read) is also an option of ``fetchcarry train KIND``, ``--name-with-dashes``; a field
holding another such dataclass (metadata :func:`nested`) contributes that dataclass's options.
The command line (:mod:`training.cli.train`) reads these fields, so no option is written
twice. Bad values raise :class:`~fetchcarry_env.errors.InputError` (the user's bad input).
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import MISSING, dataclass, field, make_dataclass
from typing import Any

from fetchcarry_env.errors import InputError
from fetchcarry_env.families import FAMILY_NAMES, get_family
from fetchcarry_env.observation import Capacity
from fetchcarry_env.observations.modes import ModeOption, get_mode, modes, shown
from training.envs import MAX_SEED

MAX_ENVS = 64  # vector envs of a PPO run (one process each beyond the first)
HELDOUT_SEED_BASE = 100_000  # held-out episode k uses HELDOUT_SEED_BASE + k (the learning checks' held-out seeds)

EPOCHS_HELP = "epochs (per iteration for dagger; default {default})"
HIDDEN_HELP = "units per hidden layer / token width (default {default})"
STEP_SIZE_HELP = "Adam step size (default {default})"
FAMILY_HELP = "scenario family (basic, push, ...)"
CAPACITY_HELP = (
    "the observation's slots the learner is trained with, e.g. objects=8,clutter=12 (the other counts the "
    "default's: objects 4, clutter 8, tables 6, obstacles 12, postures 4; recorded in config.json; "
    "default: the family's, which holds every scenario it draws)"
)


def option(
    default: Any = MISSING,
    help: str = "",
    *,
    metavar: str | None = None,
    choices: tuple[str, ...] | None = None,
    positive: bool = False,
    parse: Callable[[str], Any] | None = None,
    nargs: str | None = None,
) -> Any:
    """A dataclass field that is also a command-line option (no ``default``: a required one).

    ``help`` may say ``{default}`` (floats print with ``:g``). An ``int`` or ``float``
    field reads a number (above 0 with ``positive``); a ``bool`` field is a switch
    (``--name`` if it defaults to False, ``--no-name`` if True); ``parse`` reads the
    text itself (raising :class:`InputError`); ``nargs`` takes several values (a tuple).
    """
    metadata = {"help": help, "metavar": metavar, "choices": choices, "positive": positive, "parse": parse,
                "nargs": nargs}  # fmt: skip
    return field(default=default, metadata=metadata)


def nested(*, omit: tuple[str, ...] = ()) -> dict[str, Any]:
    """The metadata of a field holding a settings dataclass whose options (but ``omit``) join the command line.

    For example ``config: BCConfig = field(default_factory=BCConfig, metadata=nested())``:
    the options show the factory's defaults.
    """
    return {"nested": True, "omit": omit}


def seed_option() -> Any:
    """The ``seed`` field of every learner (``--seed``): the run's weights depend on it alone, on CPU."""
    return option(0, "training seed, 0 to 2**32 - 1 (default {default})", metavar="N", parse=read_seed)


def read_seed(text: str) -> int:
    """A training seed from the command line: a whole number from 0 to 2**32 - 1 (what numpy and torch take)."""
    try:
        value = int(text)
    except ValueError:
        raise InputError(f"expected a whole number, got {text[:40]!r}") from None
    if not 0 <= value <= MAX_SEED:
        raise InputError(f"a seed must be between 0 and 2**32 - 1 ({MAX_SEED}), got {text[:40]}")
    return value


def read_capacity(text: str) -> str:
    """An observation capacity ``KEY=N,...`` as text with every count (:class:`InputError` if it is not one)."""
    capacity = Capacity.parse(text)  # a CapacityError (an InputError) says what is wrong
    return ",".join(f"{name}={getattr(capacity, name)}" for name in Capacity.__dataclass_fields__)


def capacity_option() -> Any:
    """The ``capacity`` field of the learners that make their own envs (``--capacity``; None: the family's)."""
    return option(None, CAPACITY_HELP, metavar="K=N,...", parse=read_capacity)


def check_capacity_holds(capacity: str | None, families: tuple[str, ...]) -> None:
    """:class:`InputError` unless ``capacity`` (None: each family's own) holds every scenario of ``families``."""
    if capacity is None:
        return
    room = Capacity.parse(capacity)
    for name in families:
        need = get_family(name).capacity
        short = [f"{k} {getattr(need, k)} (room for {getattr(room, k)})" for k in Capacity.__dataclass_fields__
                 if getattr(need, k) > getattr(room, k)]  # fmt: skip
        if short:
            raise InputError(f"capacity {capacity} does not hold family {name}'s scenarios: {', '.join(short)}")


def check_family(name: str) -> None:
    """:class:`InputError` unless ``name`` is a scenario family of the benchmark."""
    if name not in FAMILY_NAMES:
        raise InputError(f"unknown family {name!r}: choose one of {', '.join(FAMILY_NAMES)}")


def _scenario_family(name: str) -> None:
    """:class:`InputError` unless ``name`` is a family of the benchmark or of the paper (what the env takes)."""
    try:
        get_family(name)
    except ValueError as error:  # get_family's message lists the known names
        raise InputError(str(error)) from None


def family_names(text: str) -> tuple[str, ...]:
    """``push,multi-2`` -> ``("push", "multi-2")``, each a known family (:class:`InputError` otherwise)."""
    names = tuple(name.strip() for name in text.split(",") if name.strip())
    if not names or any(name not in FAMILY_NAMES for name in names):
        raise InputError(f"expected family names separated by commas ({', '.join(FAMILY_NAMES)}), got {text!r}")
    return names


def _images_of(obs_mode: str) -> tuple[str, ...]:
    """The image keys of ``obs_mode`` (:class:`InputError` for an unknown mode)."""
    return get_mode(read_obs_mode(obs_mode)).keys


def read_obs_mode(text: str) -> str:
    """An observation mode's name (:class:`InputError` unless a mode of that name is registered)."""
    try:
        return get_mode(text).name
    except ValueError as error:
        raise InputError(str(error)) from None


def obs_mode_option(help: str) -> Any:
    """The ``obs_mode`` field of a learner's settings: any registered observation mode."""
    return option("state", f"{help} (default {{default}})", metavar="MODE", parse=read_obs_mode)


def _image_option(mode_option: ModeOption) -> Any:
    """The dataclass field of one image option of a mode, its range checked by :class:`ImageOptions`."""
    help = f"{mode_option.help} (default {{default}})"
    if mode_option.kind is str:
        return option(mode_option.default, help, choices=mode_option.choices)
    return option(mode_option.default, help, metavar="N")


def _check_image_options(self: Any) -> None:
    for mode in modes():
        for mode_option in mode.options:
            value = getattr(self, mode_option.name, None)
            problem = None if value is None else mode_option.problem(value)
            if problem is not None:
                raise InputError(f"{problem}, got {shown(value)}")


def _env_options(self: Any, obs_mode: str) -> dict[str, Any]:
    """``gym.make``'s observation keywords for ``obs_mode``: ``{}`` for ``state``, else the mode and its options."""
    mode = get_mode(obs_mode)
    if not mode.keys:
        return {}
    return {"obs_mode": obs_mode, **{name: getattr(self, name) for name in mode.option_names if hasattr(self, name)}}


ImageOptions = make_dataclass(
    "ImageOptions",
    [(o.name, o.kind, _image_option(o)) for mode in modes() for o in mode.options if o.default is not None],
    namespace={"__post_init__": _check_image_options, "env_options": _env_options},
    frozen=True,
)
ImageOptions.__module__ = __name__  # picklable as this module's (make_dataclass takes no module= before 3.12)
ImageOptions.__doc__ = """The env's image options of a run that learns from pixels (``dagger``, ``ppo``).

``bc`` reads its dataset's.

Made from the observation modes' records (:mod:`fetchcarry_env.observations.modes`): one
field per option that has a default. Only the options of the run's ``obs_mode`` reach the
env (``env_options(obs_mode)``) and the run folder's ``config.json`` (its ``observation``).
"""


@dataclass(frozen=True)
class BCConfig:
    """What a BC run trains (every field is saved in the run folder's ``config.json``)."""

    encoder: str = option(
        "mlp",
        "flat MLP, object-centric set encoder, or a small CNN over the images of --obs-mode (default {default})",
        choices=("mlp", "set", "cnn"),
    )
    hidden: int = option(256, HIDDEN_HELP, positive=True)  # units per hidden layer (mlp) or token width (set)
    epochs: int = option(60, EPOCHS_HELP, positive=True)
    batch_size: int = option(128, "minibatch size (default {default})", positive=True)
    learning_rate: float = option(1e-3, STEP_SIZE_HELP, metavar="LR", positive=True)
    weight_decay: float = 1e-5
    seed: int = seed_option()
    relative: bool = True  # append positions relative to the base (mlp: and clutter relative to goals; set: per token)
    push_scores: bool = False  # mlp: add scores from whether each push leaves a goal covered (PushScores)
    avoid_repeats: bool = True  # acting: in a state met before this episode, not the candidates chosen there
    avoid_returns: bool = False  # acting: no approach or waypoint move seen this episode to end in a state met before
    push_after_approach: bool = False  # acting: no approach right after an approach (the expert's data never has one)
    skip_delivered: bool = False  # acting: no pick of an object that stands delivered on its goal
    obs_mode: str = obs_mode_option(
        "what the network sees: state (the observation vector: mlp, set) or the images of topdown, rgbd or another "
        "registered mode (cnn; the dataset must hold them: fetchcarry dataset render)"
    )

    def __post_init__(self) -> None:
        if self.encoder not in ("mlp", "set", "cnn"):
            raise InputError(f"encoder must be 'mlp', 'set' or 'cnn', got {str(self.encoder)[:40]!r}")
        if (self.encoder == "cnn") != bool(_images_of(self.obs_mode)):
            raise InputError(
                f"encoder {self.encoder!r} with obs_mode {str(self.obs_mode)[:40]!r}: the cnn encoder reads the "
                "images of obs_mode topdown or rgbd, the mlp and set encoders the state"
            )
        if self.encoder == "cnn" and (self.avoid_returns or self.push_scores or self.skip_delivered):
            raise InputError(
                "avoid_returns, push_scores and skip_delivered read the state vector: not with the cnn encoder"
            )
        if min(self.hidden, self.epochs, self.batch_size) < 1 or self.learning_rate <= 0:
            raise InputError("hidden, epochs and batch_size must be positive, learning_rate > 0")


@dataclass(frozen=True)
class PPOOptions:
    """A PPO run's budget and settings (the defaults are the published budget)."""

    steps: int = option(20_000, "env steps in total, over all envs (default {default})", positive=True)
    n_steps: int = option(256, "env steps per rollout, over all envs (default {default})", positive=True)
    batch_size: int = 64
    n_epochs: int = 10
    learning_rate: float = option(3e-4, STEP_SIZE_HELP, metavar="LR", positive=True)
    gamma: float = 0.99
    checkpoint_every: int = option(1024, "env steps between checkpoints (default {default})", positive=True)
    encoder: str = option("mlp", "the actor's network: cnn for --obs-mode topdown or rgbd (default {default}; "
                          "with --init, the init run's)", choices=("mlp", "set", "cnn"))  # fmt: skip
    hidden: int = option(256, HIDDEN_HELP, positive=True)
    seed: int = seed_option()
    init: str | None = option(None, "a bc or dagger run folder whose network starts the actor", metavar="RUN_DIR")
    envs: int = option(
        1,
        "envs stepped side by side (default {default}; more than 1: one worker process each, env i's first "
        f"episode from seed --seed + i; at most {MAX_ENVS})",
        positive=True,
    )
    eval_every: int = option(
        2048, "env steps between evaluations on held-out seeds (default {default}; also after the last rollout)",
        positive=True,
    )  # fmt: skip
    eval_episodes: int = option(
        50, f"held-out episodes per evaluation, seeds from {HELDOUT_SEED_BASE}; 0: none (default {{default}})"
    )
    obs_mode: str = obs_mode_option(
        "what the actor and the value see: state (the observation vector) or the images of topdown, rgbd or another "
        "registered mode (with --encoder cnn)"
    )
    capacity: str | None = capacity_option()

    def __post_init__(self) -> None:
        if self.capacity is not None:
            object.__setattr__(self, "capacity", read_capacity(self.capacity))
        if min(self.steps, self.n_steps, self.batch_size, self.n_epochs, self.checkpoint_every, self.eval_every) < 1:
            raise InputError("steps, n_steps, batch_size, n_epochs, checkpoint_every and eval_every must be positive")
        if self.eval_episodes < 0:
            raise InputError(f"eval_episodes must be 0 or more, got {self.eval_episodes}")
        if not 1 <= self.envs <= min(MAX_ENVS, self.n_steps):
            raise InputError(f"envs must be from 1 to {MAX_ENVS} and at most n_steps, got {self.envs}")
        if self.learning_rate <= 0 or not 0 < self.gamma <= 1:
            raise InputError("learning_rate must be positive and gamma in (0, 1]")
        BCConfig(encoder=self.encoder, hidden=self.hidden, obs_mode=self.obs_mode)


@dataclass(frozen=True)
class DaggerOptions:
    """A DAgger run's budget (the defaults are the published budget)."""

    demonstrations: int = option(100, "expert episodes before the first iteration (default {default})", positive=True)
    iterations: int = option(4, "DAgger iterations (default {default})", positive=True)
    episodes_per_iteration: int = option(50, "learner episodes per iteration (default {default})", positive=True)
    eval_episodes: int = option(50, "held-out episodes per iteration (default {default})", positive=True)
    time_limit: float = option(10.0, "seconds per planning call of the expert (default {default})", metavar="S",
                               positive=True)  # fmt: skip
    epochs: int = option(40, EPOCHS_HELP, positive=True)  # epochs of each retraining
    nearest_moves: bool = option(
        False, "label an expert move no candidate expresses with the allowed move nearest it (default: no label)"
    )
    learner_families: tuple[str, ...] = option(
        (),
        "families the learner episodes draw from, in turn (for example push,multi-2: where learners fail most); "
        "iteration 0 and the held-out success stay on --family (default: --family)",
        metavar="NAME[,NAME...]",
        parse=family_names,
    )  # learner episode k draws from the k-th (cycled); () = the run's family
    dataset: str | None = option(
        None,
        "iteration 0 trains on the first --demonstrations episodes of this phases dataset instead of running the "
        "expert again (default: new expert episodes)",
        metavar="ID",
    )
    capacity: str | None = capacity_option()

    def __post_init__(self) -> None:
        object.__setattr__(self, "learner_families", tuple(self.learner_families))  # a list from config.json too
        if self.capacity is not None:
            object.__setattr__(self, "capacity", read_capacity(self.capacity))
        if min(self.demonstrations, self.iterations, self.episodes_per_iteration, self.eval_episodes, self.epochs) < 1:
            raise InputError("demonstrations, iterations, episodes per iteration, eval episodes, epochs must be >= 1")
        if self.time_limit <= 0:
            raise InputError(f"the time limit must be positive, got {self.time_limit}")
        for name in self.learner_families:
            _scenario_family(name)


# ------------------------------------------------- what each ``fetchcarry train KIND`` takes
@dataclass(frozen=True)
class BCRun:
    """``fetchcarry train bc``: behaviour cloning on a phases dataset (its first ``episodes``, or all)."""

    dataset: str = option(help="Minari dataset id (made with --interface phases)", metavar="ID")
    episodes: int | None = option(None, "train on the dataset's first N episodes (default: all)", positive=True)
    config: BCConfig = field(default_factory=BCConfig, metadata=nested())


@dataclass(frozen=True)
class DaggerRun:
    """``fetchcarry train dagger``: DAgger on ``family`` (the network's epochs are ``options.epochs``)."""

    family: str = option(help=FAMILY_HELP, metavar="NAME")
    options: DaggerOptions = field(default_factory=DaggerOptions, metadata=nested())
    config: BCConfig = field(default_factory=BCConfig, metadata=nested(omit=("epochs",)))
    images: ImageOptions = field(default_factory=ImageOptions, metadata=nested())

    def __post_init__(self) -> None:
        check_family(self.family)
        check_capacity_holds(self.options.capacity, (self.family, *self.options.learner_families))


@dataclass(frozen=True)
class PPORun:
    """``fetchcarry train ppo``: MaskablePPO on ``family``."""

    family: str = option(help=FAMILY_HELP, metavar="NAME")
    options: PPOOptions = field(default_factory=PPOOptions, metadata=nested())
    images: ImageOptions = field(default_factory=ImageOptions, metadata=nested())

    def __post_init__(self) -> None:
        check_family(self.family)
        check_capacity_holds(self.options.capacity, (self.family,))


@dataclass(frozen=True)
class EnsembleRun:
    """``fetchcarry train ensemble``: finished run folders combined into one policy."""

    members: tuple[str, ...] = option(help="finished run folders", metavar="RUN_DIR", nargs="+")
    avoid_returns: bool = option(
        True, "act without the episode memory that skips moves known to lead back to a state met before"
    )

    def __post_init__(self) -> None:
        object.__setattr__(self, "members", tuple(str(member) for member in self.members))
