"""MaskablePPO (sb3-contrib, unchanged) on the candidate phases, with an actor a BC run can initialise.

The env is ``FetchCarryPushPhases-v0`` with the learning reward (potential-shaped
progress; refusals cost more than moving), its flat observation vector
(``observation["observation"]``) as the policy's input, ``envs`` of them side by side
(:func:`make_vec_env`: SB3's ``DummyVecEnv`` for one, ``SubprocVecEnv`` with one forked
worker per env for more; MaskablePPO reads their masks with ``env_method("action_masks")``).
Env ``i``'s first episode is drawn with seed ``seed + i`` (SB3's ``VecEnv.seed``), its
later episodes from its own generator; a rollout is ``n_steps`` env steps over all envs
(``n_steps // envs`` each). The policy,
:class:`CandidateActorCritic`, is sb3-contrib's ``MaskableActorCriticPolicy`` whose
action head is the BC network of the chosen encoder (:mod:`training.learners.encoders`):
the observation goes straight to it (no shared layers), and a separate two-layer MLP
gives the value. So a BC or DAgger run of the same encoder initialises the actor
(``init``), and a finished PPO run's actor loads as any other run's network.

Learning curves: after every rollout, ``metrics.csv`` gains a row with the env steps,
the wall-clock seconds, and the training episodes finished in that rollout: success
rate, mean return (learning reward), mean paper return and mean travel cost (the
paper's cost, metres). A checkpoint (weights, optimiser, step count, metrics) is
written every ``checkpoint_every`` steps and at the end; a resumed run continues from
the last one (the episode under way at the interruption starts again, so a resumed run
is complete but not bit-identical to an uninterrupted one).
"""

from __future__ import annotations

import multiprocessing
import time
from dataclasses import asdict, replace
from pathlib import Path
from typing import Any

import gymnasium as gym
import numpy as np
import torch
from tqdm import tqdm

import fetchcarry_env  # noqa: F401  (registers the env ids)
from fetchcarry_env.observation import Capacity
from training.learners import runs
from training.learners.encoders import build_network
from training.learners.options import BCConfig, PPOOptions
from training.learners.runs import RunFolderError

SCALE_RESETS = 32  # scratch runs standardise the MLP's input with the observations of this many resets
VALUE_LAYERS = (256, 256)  # units of the value MLP


class FlatObservation(gym.ObservationWrapper):
    """The env's flat observation vector (``observation["observation"]``) as the observation."""

    def __init__(self, env: gym.Env) -> None:
        super().__init__(env)
        self.observation_space = env.observation_space["observation"]

    def observation(self, observation: dict[str, np.ndarray]) -> np.ndarray:
        return observation["observation"]


def make_training_env(family: str, capacity: Capacity | str | None = None) -> gym.Env:
    """``FetchCarryPushPhases-v0`` of ``family``: learning reward, flat observations (default: its capacity)."""
    extra = {} if capacity is None else {"capacity": capacity}
    return FlatObservation(gym.make(runs.ENV_ID, family=family, reward="learning", **extra))


def make_vec_env(family: str, envs: int, capacity: Capacity | str | None = None) -> Any:
    """SB3's vector env of ``envs`` training envs: in this process for one, one forked worker each for more.

    Fork starts a worker in about 0.05 s and needs no importable ``__main__``; where the
    platform has no fork, SB3's default start method is used.
    """
    from stable_baselines3.common.vec_env import DummyVecEnv, SubprocVecEnv

    makers = [lambda: make_training_env(family, capacity)] * envs
    if envs == 1:
        return DummyVecEnv(makers)
    method = "fork" if "fork" in multiprocessing.get_all_start_methods() else None
    return SubprocVecEnv(makers, start_method=method)


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
            self.action_net = build_network(
                BCConfig(**spec["config"]), Capacity(**spec["capacity"]), spec["candidates"], scale
            )
            self.optimizer = self.optimizer_class(self.parameters(), lr=lr_schedule(1), **self.optimizer_kwargs)

    return CandidateActorCritic


def _scale_observations(family: str, features: int, capacity: Capacity | None = None) -> np.ndarray:
    """Observations of a few resets (seeds 0..), to standardise a scratch MLP's input."""
    env = make_training_env(family, capacity)
    try:
        rows = [env.reset(seed=seed)[0] for seed in range(SCALE_RESETS)]
    finally:
        env.close()
    return np.asarray(rows, np.float32).reshape(len(rows), features)


def _metrics_callback(rows: list[dict[str, Any]], folder: Path, options: PPOOptions, started: float, bar: Any):
    from stable_baselines3.common.callbacks import BaseCallback

    class Curves(BaseCallback):
        """Rows of learning curves per rollout, checkpoints every ``checkpoint_every`` steps, the progress bar."""

        def __init__(self) -> None:
            super().__init__()
            self.returns = self.paper = 0.0
            self.finished: list[tuple[bool, float, float, float]] = []
            self.saved_at = rows[-1]["steps"] if rows else 0
            self.episodes = int(rows[-1]["episodes"]) if rows else 0

        def _on_step(self) -> bool:
            infos, rewards, dones = self.locals["infos"], self.locals["rewards"], self.locals["dones"]
            if isinstance(self.returns, float):  # one running sum per env, from the first step on
                self.returns, self.paper = np.zeros(len(infos)), np.zeros(len(infos))
            for i, info in enumerate(infos):  # in env order: the rows do not depend on the workers' timing
                self.returns[i] += float(rewards[i])
                self.paper[i] += float(info.get("paper_reward", 0.0))
                if dones[i]:
                    self.finished.append((bool(info.get("is_success")), float(self.returns[i]),
                                          float(self.paper[i]), float(info.get("travel_cost", 0.0))))  # fmt: skip
                    self.returns[i] = self.paper[i] = 0.0
            bar.update(len(infos))
            return True

        def _on_rollout_end(self) -> None:
            done = self.finished
            self.episodes += len(done)
            rows.append(
                {
                    "steps": self.num_timesteps,
                    "seconds": time.perf_counter() - started,
                    "episodes": self.episodes,
                    "success": float(np.mean([d[0] for d in done])) if done else float("nan"),
                    "return": float(np.mean([d[1] for d in done])) if done else float("nan"),
                    "paper_return": float(np.mean([d[2] for d in done])) if done else float("nan"),
                    "travel_cost": float(np.mean([d[3] for d in done])) if done else float("nan"),
                }
            )
            self.finished = []
            runs.write_metrics(folder, rows)
            if rows[-1]["success"] == rows[-1]["success"]:
                bar.set_postfix_str(f"success {rows[-1]['success']:.0%}", refresh=False)
            if self.num_timesteps - self.saved_at >= options.checkpoint_every:
                save_ppo_checkpoint(folder, self.model, rows)
                self.saved_at = self.num_timesteps

    return Curves()


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
    family: str, options: PPOOptions, out: str | Path, *, resume: bool = False, progress: bool = True
) -> list[dict[str, Any]]:
    """Train MaskablePPO on ``family`` into the run folder ``out``; return the learning-curve rows.

    The ``train`` of the ``ppo`` learner (:mod:`training.learners.registry`: the fields of
    :class:`~training.learners.options.PPORun` as keyword arguments). An ``options.init``
    that is not a bc or dagger run of this interface is a :class:`RunFolderError`.
    """
    torch.set_num_threads(1)
    if options.init is not None:
        init = runs.read_config(options.init)
        if init["kind"] not in ("bc", "dagger"):
            raise RunFolderError(
                f"a PPO actor starts from a bc or dagger run; {options.init} holds a {init['kind']!r} run"
            )
        options = PPOOptions(**{**asdict(options), "encoder": init["config"]["encoder"],
                                "hidden": init["config"]["hidden"]})  # fmt: skip
    config = BCConfig(encoder=options.encoder, hidden=options.hidden, seed=options.seed)
    if options.init is not None:  # the init run's network features too, so that its weights fit
        start = runs.network_config(init)
        config = replace(config, relative=start.relative, push_scores=start.push_scores)
    probe = make_training_env(family, options.capacity)  # its spaces and capacity (it connects to no physics server)
    capacity, candidates = probe.unwrapped.capacity, int(probe.action_space.n)
    features = int(probe.observation_space.shape[0])
    probe.close()
    if options.init is not None and (init["candidates"], init["features"]) != (candidates, features):
        raise RunFolderError(f"{options.init} was trained for another interface size ({init['candidates']} candidates)")
    # The init run's weights are read and checked before the run folder is made: a bad one leaves nothing behind.
    init_weights = None
    if options.init is not None:
        init_weights = _init_weights(Path(options.init), config, capacity, candidates, features)
    run_options = {"family": family, **asdict(options)}
    if options.capacity is None:
        del run_options["capacity"]  # the family's: config.json as before --capacity existed
    if resume and options.envs == 1 and _saved_without_envs(Path(out)):
        del run_options["envs"]  # a run folder from before --envs existed: it ran one env
    config_json = runs.run_config("ppo", run_options, config, capacity, candidates, features,
                             {"init": options.init, "steps": options.steps})  # fmt: skip
    folder, checkpoint = runs.start_run(out, config_json, resume=resume)
    if runs.read_config(folder).get("complete"):
        return runs.read_metrics(folder)
    torch.manual_seed(options.seed)
    actor = actor_spec(family, config, capacity, candidates, features)
    env = make_vec_env(family, options.envs, capacity)
    try:
        model = make_model(env, options, actor)
        rows = _restore(model, folder, checkpoint, options, init_weights)
        done = model.num_timesteps
        started = time.perf_counter() - (rows[-1]["seconds"] if rows else 0.0)
        with tqdm(total=options.steps, initial=done, desc=f"ppo {folder.name}", unit="step",
                  disable=not progress) as bar:  # fmt: skip
            if done < options.steps:
                model.learn(options.steps - done, callback=_metrics_callback(rows, folder, options, started, bar),
                            reset_num_timesteps=checkpoint is None)  # fmt: skip
        save_ppo_checkpoint(folder, model, rows)
        runs.finish_run(folder, model.policy.action_net, config_json)
    finally:
        env.close()
    return rows


def _saved_without_envs(out: Path) -> bool:
    """True when ``out`` holds a run whose options do not say how many envs it ran (it ran one)."""
    if not (out / runs.CONFIG_FILE).is_file():
        return False
    options = runs.read_saved(out).get("options")
    return isinstance(options, dict) and "envs" not in options


def actor_spec(family: str, config: BCConfig, capacity: Capacity, candidates: int, features: int) -> dict[str, Any]:
    """How :class:`CandidateActorCritic` builds its actor: the network's settings and its input scale (``family``'s)."""
    return {"config": asdict(config), "capacity": asdict(capacity), "candidates": candidates,
            "scale": _scale_observations(family, features, capacity).tolist()}  # fmt: skip


def make_model(env: Any, options: PPOOptions, actor: dict[str, Any]) -> Any:
    """MaskablePPO with the candidate actor-critic on ``env`` (a rollout: ``options.n_steps`` over all envs)."""
    from sb3_contrib import MaskablePPO
    from stable_baselines3.common.logger import Logger

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
        policy_kwargs={"actor": actor, "net_arch": {"pi": [], "vf": list(VALUE_LAYERS)}},
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
