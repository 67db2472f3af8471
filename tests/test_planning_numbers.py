"""The offline planner's numbers: number words of any size, and its units read by `units`."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import units
from shadowhound.planning._numbers import SPEED_UNITS, UNIT_KINDS, UNITS, to_digits
from shadowhound.planning.rules import RulePlanner

ONES = [
    "zero",
    "one",
    "two",
    "three",
    "four",
    "five",
    "six",
    "seven",
    "eight",
    "nine",
    "ten",
    "eleven",
    "twelve",
    "thirteen",
    "fourteen",
    "fifteen",
    "sixteen",
    "seventeen",
    "eighteen",
    "nineteen",
]
TENS = ["", "", "twenty", "thirty", "forty", "fifty", "sixty", "seventy", "eighty", "ninety"]


def below_thousand(n: int, british_and: bool) -> list[str]:
    """English words for 1 <= n < 1000, written independently of the planner."""
    words: list[str] = []
    hundreds, rest = divmod(n, 100)
    if hundreds:
        words += [ONES[hundreds], "hundred"]
        if rest and british_and:
            words.append("and")
    if rest >= 20:
        words.append(TENS[rest // 10])
        if rest % 10:
            words.append(ONES[rest % 10])
    elif rest:
        words.append(ONES[rest])
    return words


def in_words(n: int, british_and: bool = False) -> str:
    if n == 0:
        return "zero"
    words: list[str] = []
    for scale, name in ((10**9, "billion"), (10**6, "million"), (10**3, "thousand"), (1, "")):
        group, n = divmod(n, scale)
        if group:
            words += below_thousand(group, british_and) + ([name] if name else [])
    return " ".join(words)


@settings(max_examples=300, deadline=None)
@given(st.integers(0, 10**12 - 1), st.booleans())
def test_number_words_are_read_as_their_value(n, british_and):
    assert to_digits(in_words(n, british_and)) == str(n)


@settings(max_examples=200, deadline=None)
@given(st.integers(1, 999_999), st.integers(0, 999_999))
def test_a_larger_scale_multiplies_what_came_before(millions, rest):
    """ "one thousand million" is 10**9 (the long-scale way to say a billion), not 1,001,000."""
    text = f"{in_words(millions)} million" + (f" {in_words(rest)}" if rest else "")
    assert to_digits(text) == str(millions * 10**6 + rest)


@pytest.mark.parametrize(
    ("text", "digits"),
    [
        ("one thousand million", "1000000000"),
        ("a thousand million", "1000000000"),
        ("two thousand five hundred million", "2500000000"),
        ("five hundred thousand", "500000"),
        ("two million three thousand", "2003000"),
        ("one hundred and five", "105"),
        ("nineteen hundred", "1900"),
        ("a billion", "1000000000"),
        ("two one", "2 1"),
        ("twenty one", "21"),
        ("one point five", "1.5"),
    ],
)
def test_compound_number_words(text, digits):
    assert to_digits(text) == digits


def test_one_thousand_million_metres_is_a_billion_metres():
    plan = RulePlanner().plan("walk forward one thousand million meters")
    assert plan.steps[0].args == {"distance": 1e9}


def test_every_unit_a_sentence_may_use_is_converted_by_the_units_module():
    for name, kind in UNITS.items():
        assert units.kind_of(name) is UNIT_KINDS[kind], name
    for name in SPEED_UNITS:
        assert units.kind_of(name) is units.SPEED, name
    assert "in" not in UNITS  # "walk 2 in the kitchen"
