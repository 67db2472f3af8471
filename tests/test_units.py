"""Reading quantities with units: what people and models write, read right or refused.

The property tests build text from parts whose value is known (a number format, a unit spelling,
spacing, case) and compare `units.read` with that value times a conversion table written here,
independently of the module's own table.
"""

from __future__ import annotations

import math
from fractions import Fraction

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import units
from shadowhound.units import ANGLE, ANGULAR_SPEED, DURATION, LENGTH, SPEED, UnitError

PI = "pi"  # a factor that is a multiple of pi: compared approximately

# Unit spelling -> how many of the kind's unit (m, deg, s, m/s, rad/s) one of it is.
REFERENCE: dict[units.Kind, dict[str, Fraction | tuple[Fraction, str]]] = {
    LENGTH: {
        **dict.fromkeys(["m", "meter", "meters", "metre", "metres"], Fraction(1)),
        **dict.fromkeys(["cm", "centimeter", "centimetres"], Fraction(1, 100)),
        **dict.fromkeys(["mm", "millimeters", "millimetre"], Fraction(1, 1000)),
        **dict.fromkeys(["km", "kilometers", "kilometre"], Fraction(1000)),
        **dict.fromkeys(["in", "inch", "inches"], Fraction(254, 10000)),
        **dict.fromkeys(["ft", "foot", "feet"], Fraction(3048, 10000)),
        **dict.fromkeys(["yd", "yard", "yards"], Fraction(9144, 10000)),
        **dict.fromkeys(["mi", "mile", "miles"], Fraction(1609344, 1000)),
    },
    ANGLE: {
        **dict.fromkeys(["deg", "degs", "degree", "degrees", "°"], Fraction(1)),
        **dict.fromkeys(["turn", "turns", "revolution", "rev", "rotations"], Fraction(360)),
        **dict.fromkeys(["rad", "rads", "radian", "radians"], (Fraction(180), "/pi")),
    },
    DURATION: {
        **dict.fromkeys(["s", "sec", "secs", "second", "seconds"], Fraction(1)),
        **dict.fromkeys(["ms", "millisecond", "milliseconds"], Fraction(1, 1000)),
        **dict.fromkeys(["min", "mins", "minute", "minutes"], Fraction(60)),
        **dict.fromkeys(["h", "hr", "hour", "hours"], Fraction(3600)),
    },
    SPEED: {
        **dict.fromkeys(["m/s", "mps", "meters per second", "metre/sec"], Fraction(1)),
        **dict.fromkeys(["cm/s", "centimeters per second"], Fraction(1, 100)),
        **dict.fromkeys(
            ["km/h", "kph", "kmh", "km per hour", "kilometres/hr"], Fraction(1000, 3600)
        ),
        **dict.fromkeys(
            ["mph", "miles per hour", "miles an hour", "mi/h"], Fraction(1609344, 3600000)
        ),
        "ft/s": Fraction(3048, 10000),
    },
    ANGULAR_SPEED: {
        **dict.fromkeys(["rad/s", "radians per second", "rad/sec"], Fraction(1)),
        **dict.fromkeys(["deg/s", "°/s", "degrees per second"], (Fraction(1, 180), "*pi")),
        **dict.fromkeys(["rpm", "turns per minute", "rev/min"], (Fraction(1, 30), "*pi")),
    },
}
KINDS = list(REFERENCE)


def expected(value: Fraction, factor: Fraction | tuple[Fraction, str]) -> float:
    if isinstance(factor, Fraction):
        return float(value * factor)
    scale, how = factor
    return float(value * scale) * math.pi if how == "*pi" else float(value * scale) / math.pi


# ---- number formats: (text, exact value, may stand without a unit, may take "of a") ------------

digits = st.integers(0, 10**7)


@st.composite
def plain_numbers(draw) -> tuple[str, Fraction]:
    whole = draw(digits)
    form = draw(st.sampled_from(["int", "decimal", "dot", "trailing dot", "exponent"]))
    if form == "int":
        return str(whole), Fraction(whole)
    if form == "trailing dot":
        return f"{whole}.", Fraction(whole)
    places = draw(st.integers(1, 6))
    frac = draw(st.integers(0, 10**places - 1))
    text = f"{frac:0{places}d}"
    if form == "dot":
        return f".{text}", Fraction(frac, 10**places)
    value = whole + Fraction(frac, 10**places)
    if form == "decimal":
        return f"{whole}.{text}", value
    exponent = draw(st.integers(-8, 8))
    e = draw(st.sampled_from(["e", "E"]))
    return f"{whole}.{text}{e}{exponent}", value * Fraction(10) ** exponent


@st.composite
def fractions(draw) -> tuple[str, Fraction]:
    top, bottom = draw(st.integers(0, 999)), draw(st.integers(1, 999))
    slash = draw(st.sampled_from(["/", " / "]))
    if draw(st.booleans()):
        whole = draw(st.integers(1, 99))
        return f"{whole} {top}{slash}{bottom}", whole + Fraction(top, bottom)
    return f"{top}{slash}{bottom}", Fraction(top, bottom)


WORDS = [
    ("a", Fraction(1)),
    ("an", Fraction(1)),
    ("one", Fraction(1)),
    ("half a", Fraction(1, 2)),
    ("half of a", Fraction(1, 2)),
    ("a half", Fraction(1, 2)),
    ("a quarter of a", Fraction(1, 4)),
    ("quarter", Fraction(1, 4)),
    ("three quarters of a", Fraction(3, 4)),
    ("one and a half", Fraction(3, 2)),
    ("2 and a quarter", Fraction(9, 4)),
    ("12 and a half", Fraction(25, 2)),
]


@st.composite
def quantities(draw, kind: units.Kind) -> tuple[str, float]:
    """Text for a quantity of `kind` and the value the reference reads it as."""
    form = draw(st.sampled_from(["plain", "fraction", "words"]))
    if form == "plain":
        number, value = draw(plain_numbers())
    elif form == "fraction":
        number, value = draw(fractions())
    else:
        number, value = draw(st.sampled_from(WORDS))
    if form != "words" and draw(st.booleans()):
        sign = draw(st.sampled_from(["-", "+", "\u2212"]))
        number, value = sign + number, (-value if sign != "+" else value)
    unit, factor = draw(st.sampled_from(sorted(REFERENCE[kind].items())))
    unit = draw(st.sampled_from([unit, unit.upper(), unit.title()]))
    spaces = [" ", "  ", "\t"] if form == "words" else ["", " ", "  ", "\t"]
    space = draw(st.sampled_from(spaces))
    pad = draw(st.sampled_from(["", " ", "  "]))
    return f"{pad}{number}{space}{unit}{pad}", expected(value, factor)


def agree(got: float, want: float, text: str) -> None:
    # Units without pi convert exactly (fractions); radians are compared to the last bits.
    assert got == pytest.approx(want, rel=1e-12, abs=1e-300), text


@settings(max_examples=400, deadline=None)
@given(st.data())
def test_text_with_a_unit_is_read_like_the_reference(data):
    kind = data.draw(st.sampled_from(KINDS))
    text, want = data.draw(quantities(kind))
    agree(units.read(text, kind), want, text)


@settings(max_examples=200, deadline=None)
@given(st.data())
def test_units_without_pi_convert_exactly(data):
    kind = data.draw(st.sampled_from([LENGTH, DURATION, SPEED]))
    text, want = data.draw(quantities(kind))
    assert units.read(text, kind) == want, text


@settings(max_examples=200, deadline=None)
@given(st.sampled_from(KINDS), st.one_of(plain_numbers(), fractions()), st.sampled_from(["", " "]))
def test_a_bare_number_is_in_the_kinds_own_unit(kind, number, pad):
    text, value = number
    assert units.read(f"{pad}{text}{pad}", kind) == float(value)
    assert units.read(float(value), kind) == float(value)


@settings(max_examples=300, deadline=None)
@given(st.data())
def test_a_unit_of_another_kind_is_refused_never_read_as_a_number(data):
    kind, other = data.draw(st.permutations(KINDS).map(lambda p: p[:2]))
    text, _ = data.draw(quantities(other))
    with pytest.raises(UnitError) as info:
        units.read(text, kind)
    message = str(info.value)
    assert repr(text) in message or repr(text)[:37] in message
    assert f"not a{'n' if kind.name[0] in 'aeiou' else ''} {kind.name}" in message
    assert kind.unit_words in message  # and what is allowed


READ_RIGHT = [
    ("3cm", LENGTH, 0.03),
    ("3 cm", LENGTH, 0.03),
    ("30 cm", LENGTH, 0.3),
    ("0.3m", LENGTH, 0.3),
    ("300mm", LENGTH, 0.3),
    ("2 ft", LENGTH, 0.6096),
    ("2 feet", LENGTH, 0.6096),
    ("6 in", LENGTH, 0.1524),
    ("1.5 metres", LENGTH, 1.5),
    ("half a meter", LENGTH, 0.5),
    ("1e-1 m", LENGTH, 0.1),
    ("1 1/2 m", LENGTH, 1.5),
    ("one and a half meters", LENGTH, 1.5),
    (" 2 KM ", LENGTH, 2000.0),
    ("90deg", ANGLE, 90.0),
    ("90°", ANGLE, 90.0),
    ("90 °", ANGLE, 90.0),
    ("1/4 turn", ANGLE, 90.0),
    ("half a turn", ANGLE, 180.0),
    ("a quarter turn", ANGLE, 90.0),
    ("three quarters of a turn", ANGLE, 270.0),
    ("-90 degrees", ANGLE, -90.0),
    ("\u221290 degrees", ANGLE, -90.0),
    ("1.5 rad", ANGLE, math.degrees(1.5)),
    ("2 min", DURATION, 120.0),
    ("half an hour", DURATION, 1800.0),
    ("500ms", DURATION, 0.5),
    ("0.5 m/s", SPEED, 0.5),
    ("50 cm/s", SPEED, 0.5),
    ("3.6 km/h", SPEED, 1.0),
    ("1 rad/s", ANGULAR_SPEED, 1.0),
    ("30 deg/s", ANGULAR_SPEED, math.radians(30)),
    ("1.5", LENGTH, 1.5),
    (2, LENGTH, 2.0),
    (-0.25, ANGLE, -0.25),
]


@pytest.mark.parametrize(
    ("value", "kind", "want"), READ_RIGHT, ids=[repr(c[0]) for c in READ_RIGHT]
)
def test_what_people_and_models_write_is_read_right(value, kind, want):
    assert units.read(value, kind) == pytest.approx(want, rel=1e-12)


REFUSED = [
    ("3 cmx", LENGTH, "unknown unit 'cmx'"),
    ("3 3 m", LENGTH, "expected one number and at most one unit"),
    ("3m 2", LENGTH, "unknown unit"),
    ("nan m", LENGTH, "not a finite number"),
    ("inf", LENGTH, "not a finite number"),
    ("-Infinity m", LENGTH, "not a finite number"),
    (float("nan"), LENGTH, "not a finite number"),
    (float("inf"), ANGLE, "not a finite number"),
    ("1e999 m", LENGTH, "too large"),
    (10**400, LENGTH, "too large"),
    ("1e308 km", LENGTH, "too large"),
    ("1e308 rad", ANGLE, "too large"),
    ("3 seconds", LENGTH, "is a duration, not a length"),
    ("90 degrees", LENGTH, "is an angle, not a length"),
    ("2 m", ANGLE, "is a length, not an angle"),
    ("0.5 m", SPEED, "is a length, not a speed"),
    ("1 m/s", ANGULAR_SPEED, "is a speed, not an angular speed"),
    ("30 deg/s", ANGLE, "is an angular speed, not an angle"),
    ("1/0 turn", ANGLE, "divides by zero"),
    ("half", LENGTH, "needs a unit"),
    ("3 a m", LENGTH, "'of a' only follows a fraction"),
    ("m", LENGTH, "expected one number"),
    ("", LENGTH, "expected one number"),
    ("--3 m", LENGTH, "expected one number"),
    ("1,5 m", LENGTH, "expected one number"),
    ("three meters", LENGTH, "expected one number"),
    ("3 m" + " " * 100, LENGTH, "too long"),
    (True, LENGTH, "True is a boolean, not a length"),
    (False, ANGLE, "False is a boolean, not an angle"),
    (None, DURATION, "None is not a duration"),
    ([1], LENGTH, "[1] is not a length"),
    ({"value": 1}, LENGTH, "is not a length"),
]


@pytest.mark.parametrize(("value", "kind", "why"), REFUSED, ids=[repr(c[0])[:30] for c in REFUSED])
def test_garbage_and_wrong_kinds_are_refused_with_what_is_allowed(value, kind, why):
    with pytest.raises(UnitError) as info:
        units.read(value, kind)
    message = str(info.value)
    assert why in message
    assert f"give a number of {kind.unit_words}" in message
    assert all(u in message for u in kind.shown_units)


@settings(max_examples=500, deadline=None)
@given(
    st.sampled_from(KINDS),
    st.one_of(
        st.text(alphabet="0123456789 .+-/eEmcinftdgrasuh°/per", max_size=24),
        st.text(max_size=24),
    ),
)
def test_any_text_is_read_as_a_finite_number_or_refused(kind, text):
    try:
        value = units.read(text, kind)
    except UnitError as exc:
        assert str(exc)
    else:
        assert math.isfinite(value)
        assert any(c.isdigit() for c in text) or any(w in text.lower() for w, _ in WORDS)


def test_kinds_of_unit_names():
    assert units.kind_of("cm") is LENGTH and units.kind_of("Feet") is LENGTH
    assert units.kind_of("km/h") is SPEED and units.kind_of("degrees per second") is ANGULAR_SPEED
    assert units.kind_of("m/m") is None and units.kind_of("furlong") is None
    assert set(units.unit_names(LENGTH)) >= {"m", "cm", "mm", "ft", "in", "yd"}
