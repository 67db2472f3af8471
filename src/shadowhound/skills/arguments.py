"""Skill arguments: the base model, and the types every numeric argument is declared with.

A numeric argument is a quantity of one kind (`Length` in metres, `Angle` in degrees, `Duration`
in seconds, `Speed` in m/s, `AngularSpeed` in rad/s; `Optional...` when it may be left out) or a
`Count`. Quantities are read by `shadowhound.units`, so every caller (a planner, a model's JSON
plan or tool call, `run_plan`, HTTP, MCP) that sends "3cm" for a length gets 0.03 m, and one
that sends "3 s", `true` or "3 cmx" gets a clear refusal. `SkillArgs` refuses to define a
numeric field any other way: pydantic's own lax reading (`true` as 1) cannot come back.
"""

from __future__ import annotations

import re
import types
import typing
from typing import Annotated, Any

from pydantic import BaseModel, BeforeValidator, ConfigDict
from pydantic.fields import FieldInfo

from .. import units
from ..units import UnitError


class _Quantity:
    """Reads a quantity of one kind; None only where the argument may be left out."""

    def __init__(self, kind: units.Kind, optional: bool = False) -> None:
        self.kind, self.optional = kind, optional

    def __call__(self, value: object) -> float | None:
        if value is None and self.optional:
            return None
        return units.read(value, self.kind)


_WHOLE = re.compile(r"^\s*[+-]?[0-9]{1,9}\s*$")


def _count(value: object) -> int:
    """A whole number: 2, 2.0 or "2"; never a boolean, a fraction or other text."""
    if isinstance(value, bool):
        raise UnitError(f"{value!r} is a boolean, not a count; give a whole number such as 2")
    if isinstance(value, int):
        return value
    if isinstance(value, float) and value.is_integer():
        return int(value)
    if isinstance(value, str) and _WHOLE.match(value):
        return int(value)
    shown = repr(value) if len(repr(value)) <= 40 else repr(value)[:37] + "..."
    raise UnitError(f"{shown} is not a count; give a whole number such as 2")


Length = Annotated[float, BeforeValidator(_Quantity(units.LENGTH))]
Angle = Annotated[float, BeforeValidator(_Quantity(units.ANGLE))]
Duration = Annotated[float, BeforeValidator(_Quantity(units.DURATION))]
Speed = Annotated[float, BeforeValidator(_Quantity(units.SPEED))]
AngularSpeed = Annotated[float, BeforeValidator(_Quantity(units.ANGULAR_SPEED))]
OptionalLength = Annotated[float | None, BeforeValidator(_Quantity(units.LENGTH, True))]
OptionalAngle = Annotated[float | None, BeforeValidator(_Quantity(units.ANGLE, True))]
OptionalDuration = Annotated[float | None, BeforeValidator(_Quantity(units.DURATION, True))]
OptionalSpeed = Annotated[float | None, BeforeValidator(_Quantity(units.SPEED, True))]
OptionalAngularSpeed = Annotated[
    float | None, BeforeValidator(_Quantity(units.ANGULAR_SPEED, True))
]
Count = Annotated[int, BeforeValidator(_count)]


def _optional_count(value: object) -> int | None:
    """A whole number, or None (none given)."""
    return None if value is None else _count(value)


OptionalCount = Annotated[int | None, BeforeValidator(_optional_count)]


class SkillArgs(BaseModel):
    """Base of every skill's arguments: unknown keys are errors, numbers are typed quantities."""

    model_config = ConfigDict(extra="forbid", allow_inf_nan=False, frozen=True)

    @classmethod
    def __pydantic_init_subclass__(cls, **kwargs: Any) -> None:
        super().__pydantic_init_subclass__(**kwargs)
        for name, info in cls.model_fields.items():
            if _numeric(info.annotation) and not is_numeric(info):
                raise TypeError(
                    f"{cls.__name__}.{name}: declare a numeric skill argument as a quantity "
                    "(Length, Angle, Duration, Speed, AngularSpeed, Optional...) or a Count, "
                    "so every caller's value is read by shadowhound.units"
                )


class NoArgs(SkillArgs):
    """This skill takes no arguments."""


def _numeric(annotation: object) -> bool:
    """Whether a field's type admits a number (bool aside), also inside unions and Annotated."""
    if annotation in (int, float, complex):
        return True
    origin = typing.get_origin(annotation)
    if origin is typing.Union or origin is types.UnionType or origin is Annotated:
        return any(_numeric(arg) for arg in typing.get_args(annotation))
    return False


def argument_kind(info: FieldInfo) -> units.Kind | None:
    """The kind of quantity a skill argument is, or None (a count, text, a name)."""
    return next(
        (
            m.func.kind
            for m in info.metadata
            if isinstance(m, BeforeValidator) and isinstance(m.func, _Quantity)
        ),
        None,
    )


def is_numeric(info: FieldInfo) -> bool:
    """Whether a skill argument is a number (a quantity or a count)."""
    return argument_kind(info) is not None or any(
        isinstance(m, BeforeValidator) and m.func in (_count, _optional_count)
        for m in info.metadata
    )


# What a person typically asks for, per kind of quantity: the values of `Skill.example`.
_TYPICAL = {units.LENGTH: 1.0, units.ANGLE: 90.0, units.DURATION: 3.0}


def typical_value(info: FieldInfo) -> object | None:
    """A value people typically give this argument (1 m, 90 degrees, 3 s, 2 times, the first of
    its choices), or None when there is none to guess (free text, a speed)."""
    kind = argument_kind(info)
    if kind is not None:
        return _TYPICAL.get(kind)
    if is_numeric(info):  # a count
        return 2
    if typing.get_origin(info.annotation) is typing.Literal:
        first: object = typing.get_args(info.annotation)[0]
        return first
    return None
