"""Actions of the wrong kind (issue 8, section 4): the env raises its documented ``ValueError`` naming the problem.

Strings, object arrays, complex numbers, ragged lists and non-finite floats gave
numpy's ``TypeError`` (or worse) before; each now gets a ``ValueError`` that says what
the action holds, and a valid action still works after any of them.
"""

from __future__ import annotations

from fractions import Fraction

import gymnasium as gym
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import fetchcarry_env  # noqa: F401  (registers the id)
from fetchcarry_env.actions import action_vector
from fetchcarry_env.env import ACTION_COMPONENTS

NVEC = np.array([141, 141, 4, 4, 4])


@pytest.fixture(scope="module")
def env(request):
    from pathlib import Path

    example = Path(__file__).resolve().parents[2] / "examples" / "push_basic.json"
    env = gym.make("FetchCarryPush-v0", scenario=example)
    env.reset(seed=0)
    yield env
    env.close()


@pytest.mark.parametrize(
    ("action", "match"),
    [
        (["1", "2", "0", "0", "0"], "action must hold integers, got strings"),
        ("10000", r"must have shape \(5,\)"),
        (np.array([1, 2, 0, 0, 0], dtype=complex), "action must hold integers, got complex numbers"),
        ([1 + 0j, 2, 0, 0, 0], "got complex numbers"),
        (np.array([1, 2, 0, 0, "x"], dtype=object), "action must hold integers, got"),
        (np.array([1, 2, 0, 0, None], dtype=object), "action must hold integers, got"),
        (np.array([1, 2, 0, 0, [1]], dtype=object), "action must hold integers, got"),
        ([1, 2, 0, 0, [0, 1]], r"action must be an array of 5 integers \(x cell, y cell, heading, posture, mode\)"),
        ([1, 2, 0, 0, np.nan], "action must hold integers"),
        ([1, 2, 0, 0, np.inf], "action must hold integers"),
        (
            [1e300, 2, 0, 0, 0],
            r"x cell = <an integer of about 301 digits> is not in \[0, 141\)",
        ),
        (np.array([1, 2, 0, 0, 2**63], dtype=np.uint64), r"mode = 9223372036854775808 is not in \[0, 4\)"),
        ({"x": 1}, r"must have shape \(5,\)"),
        (None, r"must have shape \(5,\)"),
        (np.datetime64("2026-01-01"), r"must have shape"),
        (np.zeros(5, dtype="datetime64[s]"), "action must hold integers, got dates"),
    ],
)
def test_actions_of_the_wrong_kind_raise_value_error(env, action, match):
    with pytest.raises(ValueError, match=match) as info:
        env.step(action)
    assert len(str(info.value)) < 400
    env.step(np.array([0, 0, 0, 0, 0]))  # the env still works


@pytest.mark.parametrize(
    "action",
    [
        [20, 20, 0, 0, 0],
        (20, 20, 0, 0, 0),
        np.array([20, 20, 0, 0, 0], dtype=np.uint8),
        np.array([20.0, 20.0, 0.0, 0.0, 0.0]),
        np.array([20, 20, 0, 0, 0], dtype=object),
        [Fraction(20), np.float32(20), np.int16(0), False, 0],
    ],
)
def test_whole_numbers_of_any_type_are_actions(env, action):
    assert action_vector(action, NVEC, ACTION_COMPONENTS).tolist() == [20, 20, 0, 0, 0]


@settings(max_examples=200, deadline=None, derandomize=True, database=None)
@given(
    action=st.one_of(
        st.lists(
            st.one_of(
                st.integers(-(2**70), 2**70),
                st.floats(allow_nan=True, allow_infinity=True),
                st.complex_numbers(),
                st.text(max_size=3),
                st.none(),
                st.booleans(),
                st.lists(st.integers(0, 3), max_size=2),
            ),
            max_size=7,
        ),
        st.text(max_size=6),
        st.binary(max_size=6),
        st.dictionaries(st.text(max_size=2), st.integers(), max_size=2),
    )
)
def test_any_action_is_decoded_or_refused_with_value_error(action):
    try:
        vector = action_vector(action, NVEC, ACTION_COMPONENTS)
    except ValueError as error:
        assert str(error).startswith("action ") and len(str(error)) < 400
    else:
        assert vector.dtype == np.int64 and all(0 <= v < n for v, n in zip(vector.tolist(), NVEC.tolist(), strict=True))
