"""MaskablePPO (sb3-contrib, unchanged) on the candidate phases, with an actor a BC run can initialise.

The env is ``FetchCarryPushPhases-v0`` with the learning reward (potential-shaped
progress; refusals cost more than moving), its flat observation vector
(``observation["observation"]``) as the policy's input (with ``obs_mode`` ``topdown`` or
``rgbd``, that mode's images flattened instead, and a cnn actor and a cnn value over them),
``envs`` of them side by side
(:func:`make_vec_env`: SB3's ``DummyVecEnv`` for one, ``SubprocVecEnv`` with one forked
worker per env for more; MaskablePPO reads their masks with ``env_method("action_masks")``,
which answers from the masks each step's results bring along: :class:`MaskInInfo`).
Env ``i``'s first episode is drawn with seed ``seed + i`` (SB3's ``VecEnv.seed``), its
later episodes from its own generator; a rollout is ``n_steps`` env steps over all envs
(``n_steps // envs`` each). The policy,
:class:`CandidateActorCritic`, is sb3-contrib's ``MaskableActorCriticPolicy`` whose
action head is the BC network of the chosen encoder (:mod:`training.learners.encoders`):
the observation goes straight to it (no shared layers), and a separate two-layer MLP
gives the value. Given masks, it scores only the candidates some state of the batch
allows (:mod:`training.learners.allowed`: the same distribution and gradients as
sb3-contrib's masked one, in a fraction of the time; a rollout step's scores of the
flat MLP through a TorchScript trace, :class:`~training.learners.allowed.TracedScores`,
the same numbers), and Adam runs as one fused kernel. So a BC or DAgger run of the same
encoder initialises the actor (``init``), and a finished PPO run's actor loads as any
other run's network.

Learning curves (:mod:`training.learners.ppo_curves`): after every rollout,
``metrics.csv`` gains a row with the env steps, the wall-clock seconds of training
(evaluations left out), the training episodes finished in that rollout (success rate,
mean return in the learning reward, mean paper return, mean travel cost in metres) and,
every ``eval_every`` env steps and at the end, the success and travel cost of the actor on
``eval_episodes`` held-out seeds (NaN in the rows between).
A checkpoint (weights, optimiser, step count, metrics) is
written every ``checkpoint_every`` steps and at the end; a resumed run continues from
the last one (the episode under way at the interruption starts again, so a resumed run
is complete but not bit-identical to an uninterrupted one).
"""

from __future__ import annotations

import multiprocessing
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from tqdm import tqdm

import fetchcarry_env  # noqa: F401  (registers the env ids)
from fetchcarry_env.observation import Capacity
from training.envs import make_env
from training.learners import runs
from training.learners.allowed import AllowedCategorical, TracedScores, allowed_distribution
from training.learners.encoders import FlatMLP, ImageScorer, build_network, image_shape, input_size, network_input
from training.learners.options import BCConfig, ImageOptions, PPOOptions
from training.learners.ppo_curves import curves_callback, heldout_evaluator
from training.learners.runs import RunFolderError

MASK_KEY = "next_action_mask"  # MaskInInfo's key: the mask of the state a step or reset leads to
SCALE_RESETS = 32  # scratch runs standardise the MLP's input with the observations of this many resets
VALUE_LAYERS = (256, 256)  # units of the value MLP
ADAM_OPTIONS = {"eps": 1e-5, "fused": True}
"""SB3's Adam for PPO (its eps), as one fused kernel: the same update, about 7x faster on CPU than the
per-tensor loop (2.4 ms against 17 ms a step for the actor's and critic's 1.2 M weights, one thread)."""


class FlatObservation(gym.ObservationWrapper):
    """The env's flat observation vector (``observation["observation"]``) as the observation.

    With ``obs_mode`` ``topdown`` or ``rgbd``, the mode's images flattened instead (uint8,
    :func:`~training.learners.encoders.network_input`): the cnn actor and value see pixels only.
    """

    def __init__(self, env: gym.Env, obs_mode: str = "state") -> None:
        super().__init__(env)
        self.obs_mode = obs_mode
        if obs_mode == "state":
            self.observation_space = env.observation_space["observation"]
        else:
            size = input_size(env.observation_space, obs_mode)
            self.observation_space = gym.spaces.Box(0, 255, shape=(size,), dtype=np.uint8)

    def observation(self, observation: dict[str, np.ndarray]) -> np.ndarray:
        return observation["observation"] if self.obs_mode == "state" else network_input(observation, self.obs_mode)


class MaskInInfo(gym.Wrapper):
    """The mask of the state a step or reset leads to, in its ``info`` (``MASK_KEY``); none for an episode's end.

    So that a worker process sends the next state's mask with the step's results, and
    MaskablePPO's ``env_method("action_masks")`` needs no second round trip per step
    (:func:`_masks_from_infos`). The mask is the env's own ``action_masks()``.
    """

    def reset(self, **kwargs: Any) -> tuple[Any, dict[str, Any]]:
        observation, info = self.env.reset(**kwargs)
        info[MASK_KEY] = self.env.get_wrapper_attr("action_masks")()
        return observation, info

    def step(self, action: Any) -> tuple[Any, float, bool, bool, dict[str, Any]]:
        observation, reward, terminated, truncated, info = self.env.step(action)
        if not (terminated or truncated):
            info[MASK_KEY] = self.env.get_wrapper_attr("action_masks")()
        return observation, reward, terminated, truncated, info


def make_training_env(family: str, env_options: dict[str, Any] | None = None) -> gym.Env:
    """``FetchCarryPushPhases-v0`` of ``family`` with the learning reward, flat observations.

    ``env_options``: ``gym.make``'s observation mode, image options and ``capacity`` (``{}`` or None:
    the state at the family's capacity).
    """
    env_options = env_options or {}
    env = make_env(runs.INTERFACE, family=family, reward="learning", **env_options)
    return FlatObservation(env, env_options.get("obs_mode", "state"))


def make_vec_env(family: str, envs: int, env_options: dict[str, Any] | None = None) -> Any:
    """SB3's vector env of ``envs`` training envs: in this process for one, one forked worker each for more.

    Fork starts a worker in about 0.05 s and needs no importable ``__main__``; where the
    platform has no fork, SB3's default start method is used. The masks come with each
    step's results (:class:`MaskInInfo`, :func:`_masks_from_infos`).
    """
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    makers = [lambda: MaskInInfo(make_training_env(family, env_options))] * envs
    if envs == 1:
        return _masks_from_infos(DummyVecEnv(makers))
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else None
    return _masks_from_infos(SubprocVecEnv(makers, start_method=method))


def _masks_from_infos(venv: Any) -> Any:
    """``venv`` whose ``env_method("action_masks")`` answers from the masks the last step or reset sent.

    After a step, env ``i``'s mask is that of its step's info, or of its reset's info
    (SB3's ``reset_infos``) where the episode ended and the env reset itself. The mask
    is taken out of the info, so that the infos the callbacks see are the env's.
    """
    from stable_baselines3.common.vec_env import VecEnvWrapper

    class MasksFromInfos(VecEnvWrapper):
        def reset(self) -> Any:
            observation = self.venv.reset()
            self.masks = [info.pop(MASK_KEY) for info in self.venv.reset_infos]
            return observation

        def step_wait(self) -> Any:
            observation, rewards, dones, infos = self.venv.step_wait()
            ended = self.venv.reset_infos
            self.masks = [(ended[i] if done else infos[i]).pop(MASK_KEY) for i, done in enumerate(dones)]
            return observation, rewards, dones, infos

        def env_method(self, method_name: str, *args: Any, indices: Any = None, **kwargs: Any) -> list[Any]:
            if method_name != "action_masks" or args or kwargs:
                return self.venv.env_method(method_name, *args, indices=indices, **kwargs)
            return [self.masks[i].copy() for i in self._get_indices(indices)]

    return MasksFromInfos(venv)


def _policy_class() -> type:
    from sb3_contrib.common.maskable.policies import MaskableActorCriticPolicy

    class CandidateActorCritic(MaskableActorCriticPolicy):
        """sb3-contrib's masked actor-critic whose action head is a BC network (``actor``: how to build it)."""

        def __init__(self, *args: Any, actor: dict[str, Any], **kwargs: Any) -> None:
            self.actor_spec = actor
            super().__init__(*args, **kwargs)

        def _build(self, lr_schedule: Any) -> None:
            super()._build(lr_schedule)
            spec = self.actor_spec
            scale = torch.as_tensor(np.asarray(spec["scale"], np.float32))
            config = BCConfig(**spec["config"])
            self.action_net = build_network(config, Capacity(**spec["capacity"]), spec["candidates"], scale)
            if config.encoder == "cnn":  # the value: a cnn of its own over the pixels (no value MLP before it)
                self.value_net = ImageScorer(image_shape(config.obs_mode, scale.shape[1]), 1, config.hidden)
            self.optimizer = self.optimizer_class(self.parameters(), lr=lr_schedule(1), **self.optimizer_kwargs)
            flat = isinstance(self.action_net, FlatMLP) and self.action_net.push is None
            self.rollout_scores = TracedScores(self.action_net) if flat else None  # a rollout step's scores, traced

        def _latents(self, obs: torch.Tensor) -> tuple[torch.Tensor, torch.Tensor]:
            features = self.extract_features(obs)
            if self.share_features_extractor:
                return self.mlp_extractor(features)
            return self.mlp_extractor.forward_actor(features[0]), self.mlp_extractor.forward_critic(features[1])

        def _allowed(self, latent_pi: torch.Tensor, action_masks: Any, traced: bool = False) -> AllowedCategorical:
            scorer = self.rollout_scores if traced else None
            return allowed_distribution(self.action_net, latent_pi, action_masks, int(self.action_space.n), scorer)

        def forward(self, obs: torch.Tensor, deterministic: bool = False, action_masks: Any = None) -> Any:
            """Actions, values and log-probabilities; with masks, only the allowed candidates are scored."""
            if action_masks is None:
                return super().forward(obs, deterministic, action_masks)
            latent_pi, latent_vf = self._latents(obs)
            distribution = self._allowed(latent_pi, action_masks, traced=True)
            actions, log_prob = distribution.actions_and_log_prob(deterministic=deterministic)
            return actions, self.value_net(latent_vf), log_prob

        def evaluate_actions(self, obs: torch.Tensor, actions: torch.Tensor, action_masks: Any = None) -> Any:
            """Values, log-probabilities and entropies of a minibatch (scored over its allowed candidates)."""
            if action_masks is None:
                return super().evaluate_actions(obs, actions, action_masks)
            latent_pi, latent_vf = self._latents(obs)
            distribution = self._allowed(latent_pi, action_masks)
            return self.value_net(latent_vf), distribution.log_prob(actions), distribution.entropy()

        def get_distribution(self, obs: torch.Tensor, action_masks: Any = None) -> Any:
            if action_masks is None:
                return super().get_distribution(obs, action_masks)
            features = super().extract_features(obs, self.pi_features_extractor)
            return self._allowed(self.mlp_extractor.forward_actor(features), action_masks)

    return CandidateActorCritic


def _scale_observations(family: str, features: int, capacity: Capacity | None = None) -> np.ndarray:
    """Observations of a few resets (seeds 0..), to standardise a scratch MLP's input."""
    env = make_training_env(family, {"capacity": capacity})
    try:
        rows = [env.reset(seed=seed)[0] for seed in range(SCALE_RESETS)]
    finally:
        env.close()
    return np.asarray(rows, np.float32).reshape(len(rows), features)


def save_ppo_checkpoint(folder: Path, model: Any, rows: list[dict[str, Any]]) -> None:
    runs.save_checkpoint(folder, {"policy": model.policy.state_dict(), "optimizer": model.policy.optimizer.state_dict(),
                                  "steps": int(model.num_timesteps), "metrics": rows})  # fmt: skip


def _init_weights(init: Path, config: BCConfig, capacity: Capacity, candidates: int,
                  features: int) -> dict[str, torch.Tensor]:  # fmt: skip
    """The tensors of ``init``'s ``model.pt``, checked to fit the actor ``config`` builds (RunFolderError else)."""
    from training.learners.imitation import load_weights

    probe = build_network(config, capacity, candidates, torch.zeros(1, features))
    return load_weights(probe, init / runs.WEIGHTS_FILE)  # refuses what is not the network's finite tensors


def train_ppo(
    family: str, options: PPOOptions, out: str | Path, images: ImageOptions | None = None, *, resume: bool = False,
    progress: bool = True,
) -> list[dict[str, Any]]:  # fmt: skip
    """Train MaskablePPO on ``family`` into the run folder ``out``; return the learning-curve rows.

    The ``train`` of the ``ppo`` learner (:mod:`training.learners.registry`: the fields of
    :class:`~training.learners.options.PPORun` as keyword arguments). An ``options.init``
    that is not a bc or dagger run of this interface is a :class:`RunFolderError`.
    ``options.obs_mode`` ``topdown`` or ``rgbd`` (``images``: the image options) trains a
    cnn actor and a cnn value on the images alone.
    """
    torch.set_num_threads(1)
    if options.init is not None:
        init = runs.read_config(options.init)
        if init["kind"] not in ("bc", "dagger"):
            raise RunFolderError(
                f"a PPO actor starts from a bc or dagger run; {options.init} holds a {init['kind']!r} run"
            )
        options = PPOOptions(**{**asdict(options), "encoder": init["config"]["encoder"],
                                "hidden": init["config"]["hidden"],
                                "obs_mode": init["config"].get("obs_mode", "state")})  # fmt: skip
    config = BCConfig(encoder=options.encoder, hidden=options.hidden, seed=options.seed, obs_mode=options.obs_mode)
    image_options = (images or ImageOptions()).env_options(options.obs_mode)  # what the run records
    env_options = {**image_options, "capacity": options.capacity}  # what its envs are made with (None: the family's)
    if options.init is not None:  # the init run's network features too, so that its weights fit
        start = runs.network_config(init)
        config = replace(config, relative=start.relative, push_scores=start.push_scores)
    probe = make_training_env(family, env_options)  # its spaces and capacity (it connects to no physics server)
    capacity, candidates = probe.unwrapped.capacity, int(probe.action_space.n)
    features = int(probe.observation_space.shape[0])
    probe.close()
    if options.init is not None and (init["candidates"], init["features"]) != (candidates, features):
        raise RunFolderError(f"{options.init} was trained for another interface size ({init['candidates']} candidates, "
                             f"{init['features']} inputs; its images: config.json's observation)")  # fmt: skip
    # The init run's weights are read and checked before the run folder is made: a bad one leaves nothing behind.
    init_weights = None
    if options.init is not None:
        init_weights = _init_weights(Path(options.init), config, capacity, candidates, features)
    run_options = {"family": family, **asdict(options)}
    if options.obs_mode == "state":
        del run_options["obs_mode"]  # a state run's options as before observation modes (its --resume too)
    else:
        run_options["images"] = {k: v for k, v in image_options.items() if k != "obs_mode"}
    if options.capacity is None:
        del run_options["capacity"]  # the family's: config.json as before --capacity existed
    if resume:
        _drop_legacy_options(Path(out), run_options)
    config_json = runs.run_config("ppo", run_options, config, capacity, candidates, features,
                             {"init": options.init, "steps": options.steps}, image_options or None)  # fmt: skip
    folder, checkpoint = runs.start_run(out, config_json, resume=resume)
    if runs.read_config(folder).get("complete"):
        return runs.read_metrics(folder)
    torch.manual_seed(options.seed)
    actor = actor_spec(family, config, capacity, candidates, features)
    env = make_vec_env(family, options.envs, env_options)
    try:
        model = make_model(env, options, actor)
        rows = _restore(model, folder, checkpoint, options, init_weights)
        done = model.num_timesteps
        evaluate = heldout_evaluator(folder, family, capacity, options.eval_episodes, env_options)
        with tqdm(total=options.steps, initial=done, desc=f"ppo {folder.name}", unit="step",
                  disable=not progress) as bar:  # fmt: skip
            if done < options.steps:
                callback = curves_callback(rows, folder, options, bar, evaluate,
                                           lambda trained: save_ppo_checkpoint(folder, trained, rows))  # fmt: skip
                model.learn(options.steps - done, callback=callback, reset_num_timesteps=checkpoint is None)
        save_ppo_checkpoint(folder, model, rows)
        runs.finish_run(folder, model.policy.action_net, config_json)
    finally:
        env.close()
    return rows


LEGACY_OPTIONS = ("envs", "eval_every", "eval_episodes")
"""Options a run folder may not record (it was made before they existed): it resumes if they have their defaults."""


def _drop_legacy_options(out: Path, run_options: dict[str, Any]) -> None:
    """Remove from ``run_options`` the :data:`LEGACY_OPTIONS` that ``out``'s saved run lacks, where they are defaults.

    A run from before ``--envs`` ran one env; one from before the held-out evaluations
    gains them from its resumption on (its earlier rows hold NaN there).
    """
    if not (out / runs.CONFIG_FILE).is_file():
        return
    saved = runs.read_saved(out).get("options")
    if not isinstance(saved, dict):
        return
    for name in LEGACY_OPTIONS:
        if name not in saved and run_options.get(name) == PPOOptions.__dataclass_fields__[name].default:
            del run_options[name]


def actor_spec(family: str, config: BCConfig, capacity: Capacity, candidates: int, features: int) -> dict[str, Any]:
    """How :class:`CandidateActorCritic` builds its actor: the network's settings and its input scale (``family``'s)."""
    scale = np.zeros((1, features)) if config.encoder == "cnn" else _scale_observations(family, features, capacity)
    return {"config": asdict(config), "capacity": asdict(capacity), "candidates": candidates,
            "scale": scale.tolist()}  # fmt: skip


def make_model(env: Any, options: PPOOptions, actor: dict[str, Any]) -> Any:
    """MaskablePPO with the candidate actor-critic on ``env`` (a rollout: ``options.n_steps`` over all envs)."""
    from sb3_contrib import MaskablePPO
    from stable_baselines3.common.logger import Logger

    cnn = actor["config"]["encoder"] == "cnn"  # the value is a cnn over the pixels, not a value MLP
    model = MaskablePPO(
        _policy_class(),
        env,
        learning_rate=options.learning_rate,
        n_steps=max(1, options.n_steps // options.envs),
        batch_size=options.batch_size,
        n_epochs=options.n_epochs,
        gamma=options.gamma,
        seed=options.seed,  # SB3 seeds env i's first reset with seed + i
        device="cpu",
        verbose=0,
        policy_kwargs={
            "actor": actor,
            "net_arch": {"pi": [], "vf": [] if cnn else list(VALUE_LAYERS)},
            "optimizer_kwargs": ADAM_OPTIONS,
        },
    )
    model.set_logger(Logger(folder=None, output_formats=[]))  # SB3's default makes an empty folder in /tmp per run
    return model


def _restore(model: Any, folder: Path, checkpoint: dict[str, Any] | None, options: PPOOptions,
             init_weights: dict[str, torch.Tensor] | None) -> list[dict[str, Any]]:  # fmt: skip
    """Load the checkpoint (or the init run's actor) into ``model``; return the learning-curve rows so far."""
    if checkpoint is None:
        if init_weights is not None:
            model.policy.action_net.load_state_dict(init_weights)
        return []
    steps = runs.checkpoint_counter(folder, checkpoint, "steps", options.steps + options.n_steps)
    try:
        model.policy.load_state_dict(checkpoint["policy"])
        model.policy.optimizer.load_state_dict(checkpoint["optimizer"])
    except (RuntimeError, TypeError, ValueError, KeyError, AttributeError) as error:
        file = folder / runs.CHECKPOINT_FILE
        raise RunFolderError(f"{file}: it does not fit this run ({type(error).__name__})") from None
    model.num_timesteps = steps
    return [dict(r) for r in checkpoint["metrics"]]
