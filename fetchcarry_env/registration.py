"""Gymnasium registration of the fetchcarry environment ids."""

from gymnasium.envs.registration import register, registry

from fetchcarry_env.kinematics import WAIT_COST

ENV_ID = "FetchCarryPush-v0"  # the env's own MultiDiscrete phase actions
PHASES_ENV_ID = "FetchCarryPushPhases-v0"  # the same env with Discrete(K) candidate phases and exact masks
MAX_EPISODE_STEPS = 50  # phases; the expert needs at most about 4 per object plus detours


def do_nothing_return(objects: int, phases: int = MAX_EPISODE_STEPS) -> float:
    """The return of an episode that delivers nothing, travels nowhere and breaks no rule, over ``phases`` phases.

    Each phase costs ``W1`` (:data:`~fetchcarry_env.kinematics.WAIT_COST`) for each of the
    ``objects`` not at its goal: ``-W1 * objects * phases``, -500 per object over the
    env's 50 phases. The benchmark's score is 0 there.
    """
    return -WAIT_COST * objects * phases


def register_envs() -> None:
    """Register ``FetchCarryPush-v0`` and ``FetchCarryPushPhases-v0`` (idempotent).

    ``FetchCarryPushPhases-v0`` is the same env behind
    :class:`fetchcarry_env.phase_env.PhaseActions`: ``Discrete(K)`` candidate phases with
    exact masks. It takes the env's arguments plus ``layout`` (a
    :class:`fetchcarry_env.phases.PhaseLayout`), ``reward`` (``"paper"``, the env's, or
    ``"learning"``: :class:`fetchcarry_env.shaping.LearningReward`) and ``gamma``.

    Both ids vectorise with ``gym.make_vec(id, num_envs=N, vectorization_mode="sync" |
    "async", **env_arguments)``: sub-env ``i`` of ``reset(seed=s)`` is the single env
    reset with ``seed=s + i``, and MaskablePPO's masks are ``venv.call("action_masks")``
    (one array per sub-env). The vector env declares its autoreset mode in
    ``metadata["autoreset_mode"]`` (Gymnasium's ``NEXT_STEP`` unless
    ``vector_kwargs={"autoreset_mode": ...}`` says otherwise): with ``NEXT_STEP`` the
    step after an episode's end resets that sub-env and ignores its action, so the mask
    read in between is the final state's; with ``SAME_STEP`` the reset comes at once
    (``info["final_obs"]``) and the mask is the new episode's. An env connects to
    PyBullet on its first reset, so ``AsyncVectorEnv``'s probe env in the parent costs no
    physics server (fork starts a worker in about 0.05 s).
    """
    if ENV_ID not in registry:
        register(
            id=ENV_ID,
            entry_point="fetchcarry_env.env:FetchCarryPushEnv",
            max_episode_steps=MAX_EPISODE_STEPS,
        )
    if PHASES_ENV_ID not in registry:
        register(
            id=PHASES_ENV_ID,
            entry_point="fetchcarry_env.phase_env:make_phase_env",
            max_episode_steps=MAX_EPISODE_STEPS,
        )
