"""Gymnasium registration of the fetchcarry environment ids."""

from gymnasium.envs.registration import register, registry

MAX_EPISODE_STEPS = 50  # phases; the expert needs at most about 4 per object plus detours


def register_envs() -> None:
    """Register ``FetchCarryPush-v0`` (idempotent)."""
    if "FetchCarryPush-v0" not in registry:
        register(
            id="FetchCarryPush-v0",
            entry_point="fetchcarry_env.env:FetchCarryPushEnv",
            max_episode_steps=MAX_EPISODE_STEPS,
        )
