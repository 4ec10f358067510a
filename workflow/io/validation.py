"""Settings as plain dataclasses, validated by pydantic only where data enters.

Config and campaign settings are frozen standard-library dataclasses: every job can
import and build them without pydantic, whose import and schema building cost a
run-analysis job about 0.2 s of start-up. pydantic validates them (types, the
``annotated_types`` bounds in their annotations, :class:`After` checks, unknown
keys) in :func:`validate`, which the workflow calls once, where config.yaml and
campaign.yaml are read.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import Annotated, Any, TypeVar

from annotated_types import Ge, Lt

__all__ = [
    "T",
    "Seed",
    "FORBID_UNKNOWN_KEYS",
    "UNKNOWN_KEY_ERRORS",
    "MISSING_KEY_ERRORS",
    "After",
    "validate",
]


T = TypeVar("T")

Seed = Annotated[int, Ge(0), Lt(2**63)]
"""A random generator's seed: NumPy takes only non-negative integers, and the outputs that
record it hold a signed 64-bit integer."""

# Upper bounds: every count, iteration and sample number has one, so that a setting cannot
# take the machine (2 cores, 24 GiB, shared) for hours or allocate what it does not have;
# each bound sits where more no longer changes a result the physics or the statistics can
# resolve, with the cost at the bound stated beside it.

FORBID_UNKNOWN_KEYS = {"extra": "forbid"}
"""``__pydantic_config__`` of a settings dataclass: an unknown key is an error."""

UNKNOWN_KEY_ERRORS = {"extra_forbidden", "unexpected_keyword_argument"}
"""pydantic error types of an unknown key (the second for dataclasses)."""

MISSING_KEY_ERRORS = {"missing", "missing_argument"}
"""pydantic error types of a required key left out (the second for dataclasses)."""


class After:
    """``Annotated`` marker: once pydantic has validated the field's type and bounds,
    ``check(value)`` returns the value to keep or raises ``ValueError`` with the
    reason, which pydantic reports at the field's own key."""

    def __init__(self, check: Callable[[Any], Any]):
        self.check = check

    def __get_pydantic_core_schema__(self, source: Any, handler: Any) -> Any:
        from pydantic_core import core_schema

        return core_schema.no_info_after_validator_function(self.check, handler(source))


def validate(settings_type: type[T], raw: Any) -> T:
    """``raw`` (parsed YAML) validated into ``settings_type``.

    Raises
    ------
    pydantic.ValidationError
        Every problem, each with the key path (``loc``) where it sits.
    """
    from pydantic import TypeAdapter

    return TypeAdapter(settings_type).validate_python(raw)
