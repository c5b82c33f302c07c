"""The user's bad input has one base class; its name before 0.2 still imports, with a warning."""

from __future__ import annotations

import pytest

from fetchcarry_env import errors
from fetchcarry_env.errors import InputError


def test_the_old_name_is_the_same_class_and_says_it_is_deprecated() -> None:
    with pytest.warns(DeprecationWarning, match="UsageError is now InputError"):
        from fetchcarry_env.errors import UsageError
    assert UsageError is InputError and issubclass(InputError, ValueError)


def test_any_other_missing_name_is_an_attribute_error() -> None:
    with pytest.raises(AttributeError, match="no attribute 'UsageErrors'"):
        errors.UsageErrors  # noqa: B018
