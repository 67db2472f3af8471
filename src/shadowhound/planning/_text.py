"""Small text helpers the offline planner's word tables and patterns are written with.

Word lists kept as one string, regex alternations of phrases, and whitespace clean-up; nothing
here knows any English words.
"""

from __future__ import annotations

import re
from collections.abc import Iterable


def words(text: str, sep: str | None = None) -> list[str]:
    """Split a word list written as one string; tables stay short and readable that way."""
    return text.split(sep)


def alternation(phrases: Iterable[str]) -> str:
    """A regex alternation of phrases, longest first, any run of spaces between words."""
    longest_first = sorted(phrases, key=len, reverse=True)
    return "|".join(re.escape(p).replace(r"\ ", r"\s+") for p in longest_first)


def canon(text: str) -> str:
    """`text` with runs of whitespace as single spaces, as the word tables are written."""
    return " ".join(text.split())
