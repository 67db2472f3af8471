"""Strict JSON out: whatever numbers a structure holds, what is written parses strictly."""

from __future__ import annotations

import io
import math
from dataclasses import dataclass

import pytest
from hypothesis import given
from hypothesis import strategies as st

from shadowhound import jsonout
from tests.strict_json import strict_loads

scalars = st.one_of(
    st.none(),
    st.booleans(),
    st.integers(min_value=-(2**70), max_value=2**70),
    st.floats(allow_nan=True, allow_infinity=True),
    st.sampled_from([math.nan, math.inf, -math.inf, 1e308, -1e308, 5e-324, -0.0]),
    st.text(max_size=8),
)
nested = st.recursive(
    scalars,
    lambda inner: st.one_of(
        st.lists(inner, max_size=4),
        st.lists(inner, max_size=4).map(tuple),
        st.dictionaries(st.text(max_size=6), inner, max_size=4),
    ),
    max_leaves=25,
)


def same_where_finite(sent: object, read: object) -> None:
    """`read` is `sent` with every non-finite float as None (tuples read back as lists)."""
    if isinstance(sent, float) and not math.isfinite(sent):
        assert read is None
    elif isinstance(sent, float):
        assert isinstance(read, float) and (read == sent)
    elif isinstance(sent, (list, tuple)):
        assert isinstance(read, list) and len(read) == len(sent)
        for a, b in zip(sent, read, strict=True):
            same_where_finite(a, b)
    elif isinstance(sent, dict):
        assert isinstance(read, dict) and read.keys() == sent.keys()
        for key in sent:
            same_where_finite(sent[key], read[key])
    else:
        assert read == sent and type(read) is type(sent)


@given(nested)
def test_any_structure_is_written_as_strict_json_keeping_every_finite_value(value):
    for options in ({}, {"separators": (",", ":")}, {"indent": 2, "sort_keys": True}):
        same_where_finite(value, strict_loads(jsonout.dumps(value, **options)))


@given(nested)
def test_dump_writes_what_dumps_returns(value):
    out = io.StringIO()
    jsonout.dump(value, out, default=str)
    assert out.getvalue() == jsonout.dumps(value, default=str)


@dataclass
class Odometry:
    x: float


def test_what_default_makes_of_an_object_is_made_finite_too():
    text = jsonout.dumps({"odom": Odometry(math.nan)}, default=lambda o: o.__dict__)
    assert strict_loads(text) == {"odom": {"x": None}}
    assert strict_loads(jsonout.dumps([Odometry(math.inf)], default=str)) == ["Odometry(x=inf)"]


def test_a_non_finite_dict_key_is_written_as_null():
    assert strict_loads(jsonout.dumps({math.nan: 1, 2.5: 2})) == {"null": 1, "2.5": 2}


def test_what_is_not_json_is_still_refused():
    with pytest.raises(TypeError):
        jsonout.dumps({"x": math.nan, "what": object()})
    loop: list[object] = [math.nan]
    loop.append(loop)
    with pytest.raises(ValueError, match="Circular"):
        jsonout.dumps(loop)


@pytest.mark.parametrize(
    ("value", "digits", "expected"),
    [(1.23456, 2, 1.23), (math.nan, 2, None), (-math.inf, None, None), (3.0, None, 3.0)],
)
def test_number_rounds_a_finite_value_and_gives_none_for_the_rest(value, digits, expected):
    assert jsonout.number(value, digits) == expected


def test_the_strict_reader_refuses_what_python_writes_for_nan():
    """So the tests above cannot pass with a reader that takes anything."""
    for text in ("[NaN]", '{"x": Infinity}', "-Infinity"):
        with pytest.raises(ValueError, match="not JSON"):
            strict_loads(text)
