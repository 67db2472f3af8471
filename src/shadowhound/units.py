"""Quantities with units: the one reader of numbers that people and models write for the robot.

    read(1.5, LENGTH) == read("150 cm", LENGTH) == read("150cm", LENGTH) == 1.5   # metres
    read("90°", ANGLE) == read("1/4 turn", ANGLE) == 90.0                         # degrees
    read("2 min", DURATION) == 120.0                                             # seconds

A bare number is in the kind's own unit (`Kind.unit`); text may add one unit of the same kind
(long or short, singular or plural, any spacing, any case). The number may be written in digits
("1.5", ".5", "1e-1"), as a fraction ("1/4", "1 1/2"), or with a few words ("a", "half",
"a quarter", "three quarters", "1 and a half"; words need a unit: "half a meter").

Anything that cannot be read for certain is refused with a `UnitError` naming the value and what
is allowed, never guessed: a boolean, a unit of another kind ("3 s" for a length), an unknown
unit ("3 cmx"), text that is not one number and one unit ("3 3 m"), a number that is not finite
or too large ("nan m", "1e999 m"). Skill arguments (`skills/arguments.py`) and the offline
planner read every quantity through this module, so "3cm" means 0.03 m on every path.

Conversions are exact where the units are (fractions, not floats), so "3 ft" is 0.9144 m.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from fractions import Fraction

from .errors import UnitError

__all__ = [
    "ANGLE",
    "ANGULAR_SPEED",
    "DURATION",
    "KINDS",
    "LENGTH",
    "SPEED",
    "Kind",
    "UnitError",
    "kind_of",
    "read",
    "unit_names",
]


@dataclass(frozen=True)
class Kind:
    """What a quantity measures, and the unit bare numbers and results are in."""

    name: str  # "length"
    unit: str  # "m": a bare number is in this unit, and `read` returns this unit
    unit_words: str  # "metres"
    shown_units: tuple[str, ...]  # units named in messages
    example: str  # text with a unit, for messages


LENGTH = Kind("length", "m", "metres", ("m", "cm", "mm", "km", "in", "ft", "yd", "mi"), "30 cm")
ANGLE = Kind("angle", "deg", "degrees", ("deg", "°", "rad", "turn"), "1/4 turn")
DURATION = Kind("duration", "s", "seconds", ("s", "ms", "min", "h"), "2 min")
SPEED = Kind("speed", "m/s", "metres per second", ("m/s", "cm/s", "km/h", "mph"), "50 cm/s")
ANGULAR_SPEED = Kind(
    "angular speed", "rad/s", "radians per second", ("rad/s", "deg/s", "rpm"), "30 deg/s"
)
KINDS = (LENGTH, ANGLE, DURATION, SPEED, ANGULAR_SPEED)


@dataclass(frozen=True)
class _Unit:
    """A unit as `factor * pi**pi_power` of its kind's reference unit (m, deg, s, m/s, deg/s)."""

    kind: Kind
    factor: Fraction
    pi_power: int = 0

    def per(self, other: _Unit) -> Fraction | float:
        """How many `other` one of this unit is (exact when no pi is involved)."""
        ratio = self.factor / other.factor
        power = self.pi_power - other.pi_power
        return ratio if power == 0 else float(ratio) * math.pi**power


_UNITS: dict[str, _Unit] = {}


def _define(kind: Kind, factor: Fraction | int | str, names: str, pi_power: int = 0) -> None:
    for name in names.split():
        _UNITS[name] = _Unit(kind, Fraction(factor), pi_power)


_define(LENGTH, 1, "m meter meters metre metres mtr mtrs")
_define(LENGTH, Fraction(1, 100), "cm centimeter centimeters centimetre centimetres")
_define(LENGTH, Fraction(1, 1000), "mm millimeter millimeters millimetre millimetres")
_define(LENGTH, 1000, "km kilometer kilometers kilometre kilometres")
_define(LENGTH, "0.0254", "in inch inches")
_define(LENGTH, "0.3048", "ft foot feet")
_define(LENGTH, "0.9144", "yd yds yard yards")
_define(LENGTH, "1609.344", "mi mile miles")
_define(ANGLE, 1, "deg degs degree degrees °")
_define(ANGLE, 180, "rad rads radian radians", pi_power=-1)
_define(ANGLE, 360, "turn turns rev revs revolution revolutions rotation rotations")
_define(ANGLE, 360, "circle circles spin spins")
_define(DURATION, 1, "s sec secs second seconds")
_define(DURATION, Fraction(1, 1000), "ms msec msecs millisecond milliseconds")
_define(DURATION, 60, "min mins minute minutes")
_define(DURATION, 3600, "h hr hrs hour hours")
# Speeds are composed ("km/h", "meters per second", "deg/s"); these are their one-word names.
_define(SPEED, 1, "mps")
_define(SPEED, Fraction(1000, 3600), "kph kmh")
_define(SPEED, Fraction("1609.344") / 3600, "mph")
_define(ANGULAR_SPEED, Fraction(360, 60), "rpm")

_COMPOSED = {(LENGTH, DURATION): SPEED, (ANGLE, DURATION): ANGULAR_SPEED}
_PER = re.compile(r"^(.+?)\s*(?:/|\s+per\s+|\s+an?\s+)\s*(\S.*)$")


def _unit(name: str) -> _Unit | None:
    name = " ".join(name.lower().split())
    if name in _UNITS:
        return _UNITS[name]
    m = _PER.match(name)
    if m is None:
        return None
    top, bottom = _UNITS.get(m.group(1)), _UNITS.get(m.group(2))
    if top is None or bottom is None or (top.kind, bottom.kind) not in _COMPOSED:
        return None
    return _Unit(
        _COMPOSED[top.kind, bottom.kind], top.factor / bottom.factor, top.pi_power - bottom.pi_power
    )


def kind_of(unit: str) -> Kind | None:
    """The kind a unit measures ("cm" -> LENGTH, "km/h" -> SPEED), or None if unknown."""
    found = _unit(unit)
    return found.kind if found is not None else None


def unit_names(kind: Kind) -> list[str]:
    """Every one-word name of a unit of `kind` (composed speeds such as "km/h" not listed)."""
    return [name for name, unit in _UNITS.items() if unit.kind is kind]


# ---- reading -------------------------------------------------------------------------------

_MAX_TEXT = 80
_MAX_EXPONENT = 400  # beyond it a float is 0 or infinite; exact arithmetic would only cost time
_DECIMAL = r"(?:[0-9]+(?:\.[0-9]*)?|\.[0-9]+)(?:e[+-]?[0-9]+)?"
_FRACTION = r"(?:[0-9]+\s+)?[0-9]+\s*/\s*[0-9]+"
_WORDS: dict[str, Fraction] = {
    "a": Fraction(1), "an": Fraction(1), "one": Fraction(1),
    "half": Fraction(1, 2), "a half": Fraction(1, 2), "one half": Fraction(1, 2),
    "quarter": Fraction(1, 4), "a quarter": Fraction(1, 4), "one quarter": Fraction(1, 4),
    "three quarters": Fraction(3, 4), "three quarter": Fraction(3, 4),
}  # fmt: skip
_WORD = "|".join(sorted((w.replace(" ", r"\s+") for w in _WORDS), key=len, reverse=True))
_AND_A = r"(?:[0-9]+|one)\s+and\s+(?:a|one)\s+(?:half|quarter)"
_QUANTITY = re.compile(
    rf"^(?P<sign>[+-]?)\s*"
    # words first: "2 and a half m" is one number, not 2 in a unit called "and a half m"
    rf"(?:(?P<words>(?:{_AND_A}|{_WORD})(?=\s|$))"
    rf"|(?P<decimal>{_DECIMAL})|(?P<fraction>{_FRACTION}))"
    # "half a meter", "1/4 of a turn": only a fraction may be followed by "of a"
    rf"(?P<of>\s+(?:of\s+)?(?:a|an)(?=\s))?"
    r"\s*(?P<unit>[^\s0-9.,+/-].*?)?\s*$",
    re.IGNORECASE,
)
_NOT_FINITE = re.compile(r"(?<![a-z])(?:nan|inf|infinity)(?![a-z])", re.IGNORECASE)


def read(value: object, kind: Kind) -> float:
    """`value` (a number, or text with a number and an optional unit) in `kind.unit`.

    Raises UnitError, whose message names the value and what is allowed, for anything that
    is not certainly a quantity of this kind.
    """
    if isinstance(value, bool):
        raise UnitError(f"{value!r} is a boolean, not {_a(kind.name)}; {allowed(kind)}")
    if isinstance(value, int | float):
        return _finite(value, value, kind)
    if not isinstance(value, str):
        raise UnitError(f"{_show(value)} is not {_a(kind.name)}; {allowed(kind)}")
    return _read_text(value, kind)


def allowed(kind: Kind) -> str:
    """What `read` accepts for `kind`, as the second half of an error message."""
    return (
        f"give a number of {kind.unit_words}, or text with {_a(kind.name)} unit "
        f"({', '.join(kind.shown_units)}) such as '{kind.example}'"
    )


def format_number(value: float) -> str:
    """A number as people write it: 2 rather than 2.0; exact otherwise (0.1, 1e+20)."""
    if value == int(value) and abs(value) < 1e15:
        return str(int(value))
    return repr(value)


def _read_text(text: str, kind: Kind) -> float:
    shown = _show(text)
    if len(text) > _MAX_TEXT:
        raise UnitError(f"{shown} is too long to be {_a(kind.name)}; {allowed(kind)}")
    clean = text.strip().replace("\u2212", "-")  # a typographic minus sign is a minus sign
    m = _QUANTITY.match(clean)
    if m is None:
        if _NOT_FINITE.search(clean):
            raise UnitError(f"{shown} is not a finite number; {allowed(kind)}")
        raise UnitError(
            f"{shown} is not {_a(kind.name)}: expected one number and at most one "
            f"unit; {allowed(kind)}"
        )
    if m.group("of") and not (m.group("fraction") or _is_fraction_word(m.group("words"))):
        raise UnitError(
            f"{shown} is not {_a(kind.name)}: 'of a' only follows a fraction, as in "
            f"'half a meter'; {allowed(kind)}"
        )
    number = _number(m, shown, kind)
    name = m.group("unit")
    if name is None:
        if m.group("words") or m.group("of"):
            raise UnitError(f"{shown} needs a unit after the number; {allowed(kind)}")
        return _finite(number, text, kind)
    unit = _unit(name)
    if unit is None:
        raise UnitError(f"{shown}: unknown unit '{name}'; {allowed(kind)}")
    if unit.kind is not kind:
        raise UnitError(f"{shown} is {_a(unit.kind.name)}, not {_a(kind.name)}; {allowed(kind)}")
    ratio = unit.per(_own_unit(kind))
    if isinstance(ratio, Fraction) and isinstance(number, Fraction):
        return _finite(number * ratio, text, kind)
    return _finite(float(number) * float(ratio), text, kind)


def _is_fraction_word(words: str | None) -> bool:
    return (
        words is not None
        and "and" not in words.lower().split()
        and _WORDS[" ".join(words.lower().split())] < 1
    )


def _number(m: re.Match[str], shown: str, kind: Kind) -> Fraction | float:
    sign = -1 if m.group("sign") == "-" else 1
    if m.group("decimal"):
        digits = m.group("decimal")
        exponent = re.search(r"e([+-]?[0-9]+)$", digits, re.IGNORECASE)
        if exponent and abs(int(exponent.group(1))) > _MAX_EXPONENT:
            return sign * float(digits)  # 0.0 or inf; inf is refused by _finite
        return sign * Fraction(digits)
    if m.group("fraction"):
        head, bottom = m.group("fraction").split("/")
        parts = head.split()
        if int(bottom) == 0:
            raise UnitError(f"{shown} divides by zero; {allowed(kind)}")
        whole = int(parts[0]) if len(parts) == 2 else 0
        return sign * (whole + Fraction(int(parts[-1]), int(bottom)))
    words = " ".join(m.group("words").lower().split())
    if " and " in words:
        whole_word, rest = words.split(" and ", 1)
        whole_value = Fraction(1) if whole_word == "one" else Fraction(int(whole_word))
        return sign * (whole_value + _WORDS[rest.split()[-1]])
    return sign * _WORDS[words]


def _own_unit(kind: Kind) -> _Unit:
    unit = _unit(kind.unit)
    assert unit is not None, f"{kind.name}: its unit {kind.unit!r} is not defined"
    return unit


def _finite(number: Fraction | float, original: object, kind: Kind) -> float:
    try:
        result = float(number)
    except OverflowError:
        result = math.inf
    if not math.isfinite(result):
        # Text and integers have finite digits: their only fault can be their size.
        what = "is too large" if isinstance(original, str | int) else "is not a finite number"
        raise UnitError(f"{_show(original)} {what}; {allowed(kind)}")
    return result


def _a(noun: str) -> str:
    return f"an {noun}" if noun[0] in "aeiou" else f"a {noun}"


def _show(value: object) -> str:
    text = repr(value)
    return text if len(text) <= 40 else text[:37] + "..."
