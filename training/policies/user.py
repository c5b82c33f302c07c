"""A user's own policy (``package.module:factory``), checked: what goes wrong in it is the user's bad input.

:func:`user_policy` calls the factory with the env and checks what it gives; the
:class:`UserPolicy` it returns checks every answer of ``predict``. Each problem is a
:class:`~training.errors.BenchmarkError` (an ``InputError``: exit 2 on the command line)
naming ``module:factory``, the way a script names the line that failed, not a crash:

- the factory raises (the error and the file and line where it was raised);
- it returns something without a callable ``predict``, or a ``predict`` that cannot be
  called as the episode loop calls it: ``predict(observation, state=..., episode_start=...,
  deterministic=...)``, and ``action_masks=...`` if it takes them (stable-baselines3's own
  ``PPO.predict`` does not; a ``**kwargs`` takes everything);
- ``predict`` raises, returns something other than an ``(action, state)`` pair, or an
  action that is not one of the env's action space (Gymnasium's ``space.contains``; for
  a ``Discrete`` space, as the episode loop reads it, any one-element integer array too).

The policy's other attributes (``reset``, ``stats``, ``last_decision``) are its own, read through.
"""

from __future__ import annotations

import functools
import inspect
import reprlib
import traceback
from collections.abc import Callable
from typing import Any

import numpy as np
from gymnasium import spaces

from training.errors import BenchmarkError

PROTOCOL = "predict(observation, state=None, episode_start=None, deterministic=False, action_masks=None)"
"""What a policy has: stable-baselines3's ``predict`` (``action_masks`` optional), returning ``(action, state)``."""

_SHORT = reprlib.Repr()  # how a user's value is shown: abbreviated past 60 characters
_SHORT.maxstring = _SHORT.maxother = 60


def user_policy(name: str, factory: Callable[[Any], Any], env: Any) -> UserPolicy:
    """``factory(env)``, checked to be a policy (see the module docstring), as a :class:`UserPolicy` for ``env``."""
    try:
        made = factory(env)
    except Exception as error:  # the user's code: its failure is the user's to fix
        raise BenchmarkError(f"policy {name!r}: the factory raised {describe_raised(error)}") from error
    check_policy(name, made)
    return UserPolicy(name, made, env.action_space)


def check_policy(name: str, made: Any) -> None:
    """``BenchmarkError`` unless ``made`` has a ``predict`` the episode loop can call (the protocol's keywords)."""
    predict = getattr(made, "predict", None)
    if not callable(predict):
        raise BenchmarkError(f"policy {name!r}: the factory returned {shown(made)}, not a policy (one with {PROTOCOL})")
    try:
        signature = inspect.signature(predict)
    except (TypeError, ValueError):
        return  # a signature Python cannot read (a builtin): its answers are still checked
    try:
        signature.bind(None, state=None, episode_start=None, deterministic=True)
    except TypeError as error:
        raise BenchmarkError(
            f"policy {name!r}: the predict of {shown(made)} cannot be called as {PROTOCOL} ({error})"
        ) from None


class UserPolicy:
    """A user's policy whose every ``predict`` answer is checked to be ``(action, state)`` with an env action.

    ``predict`` has the wrapped policy's own signature (:func:`functools.wraps`), so the
    episode loop hands it ``action_masks`` exactly when the policy takes them.
    """

    def __init__(self, name: str, policy: Any, action_space: spaces.Space) -> None:
        self._name = name
        self._policy = policy
        self._space = action_space
        self.predict = self._checking(policy.predict)

    def __getattr__(self, attribute: str) -> Any:
        """The wrapped policy's own attributes (``reset``, ``stats``, ``last_decision``, ...)."""
        policy = self.__dict__.get("_policy")
        if policy is None:
            raise AttributeError(attribute)
        return getattr(policy, attribute)

    def _checking(self, predict: Callable[..., Any]) -> Callable[..., Any]:
        @functools.wraps(predict)
        def checked(observation: Any, *args: Any, **kwargs: Any) -> tuple[Any, Any]:
            try:
                answer = predict(observation, *args, **kwargs)
            except Exception as error:  # the user's code
                raise BenchmarkError(f"policy {self._name!r}: predict raised {describe_raised(error)}") from error
            return self._checked(answer)

        return checked

    def _checked(self, answer: Any) -> tuple[Any, Any]:
        if not (isinstance(answer, tuple) and len(answer) == 2):
            raise BenchmarkError(
                f"policy {self._name!r}: predict must return (action, state), as stable-baselines3's does; "
                f"it returned {shown(answer)}"
            )
        if not is_action(answer[0], self._space):
            raise BenchmarkError(
                f"policy {self._name!r}: predict answered {shown(answer[0])}, which is not an action of {self._space}"
            )
        return answer


def is_action(action: Any, space: spaces.Space) -> bool:
    """Whether ``action`` is one of ``space`` (integers only; a one-element array stands for a ``Discrete`` index)."""
    try:
        array = np.asarray(action)
    except (TypeError, ValueError):  # a ragged sequence
        return False
    if not np.issubdtype(array.dtype, np.integer):
        return False
    if isinstance(space, spaces.Discrete) and array.size == 1:
        array = array.reshape(())
    return bool(space.contains(array))


def describe_raised(error: BaseException) -> str:
    """``Type: message (file, line N)``: an exception and the last line of code it went through."""
    frames = traceback.extract_tb(error.__traceback__)
    where = f" ({frames[-1].filename}, line {frames[-1].lineno})" if frames else ""
    return f"{type(error).__name__}: {error}{where}"


def shown(value: Any) -> str:
    """A user's value in a message, kept short: its ``repr`` (abbreviated) and its type."""
    return f"{_SHORT.repr(value)} ({type(value).__name__})"
