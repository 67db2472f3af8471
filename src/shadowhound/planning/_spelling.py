"""Forgiving spelling for the offline planner: misspellings of its own words, read by edit
distance, never guessed when a word could mean two things.

The vocabulary is every word the planner itself knows: its word tables, the words in its phrase
patterns, number words and unit names. A word outside it ("trun", "forwrd", "sti") is read as
the one known word nearest to it when that word is unique, starts with the same letter and is
close enough: one edit (an insertion, deletion, substitution or swap of neighbours) for words of
up to six letters, two for longer ones. The first letter must match because people rarely
mistype it and because it keeps real words of other meanings ("talk", "lift") from being read
as commands ("walk", "left"). Corrections are only tried on a clause the planner did not
understand as written, and kept only if it then understands it whole.
"""

from __future__ import annotations

import functools
import itertools
import re
from dataclasses import dataclass, field
from types import ModuleType
from typing import Any

from shadowhound import units
from shadowhound.planning import (
    _english,
    _memory_phrases,
    _numbers,
    _phrases,
    _vocabulary,
    _watches,
)

from ..typos import distance
from ..typos import limit as _limit

_WORD = re.compile(r"[a-z]+")
MIN_LENGTH = 3  # shorter words ("ot", "m") have too many neighbours to guess from


def _pattern_words(value: Any) -> set[str]:
    if isinstance(value, re.Pattern):
        return set(re.findall(r"[a-z]{2,}", value.pattern))
    if isinstance(value, (list, tuple)):
        return {w for item in value for w in _pattern_words(item)}
    return set()


def _table_words(*tables: Any) -> set[str]:
    return {w for table in tables for phrase in table for w in _WORD.findall(phrase)}


@functools.cache
def known_words() -> frozenset[str]:
    """Every word the offline planner reads: its tables, its patterns, numbers and units."""
    modules: list[ModuleType] = [_english, _memory_phrases, _numbers, _phrases, _watches]
    # Contractions are gone once a clause is normalised ("don't" is "do not" by then).
    patterns = {
        w
        for m in modules
        for v in vars(m).values()
        if v is not _english._CONTRACTION
        for w in _pattern_words(v)
    }
    v = _vocabulary
    tables = _table_words(
        v.DIRECTIONS,
        v.ADVERBS,
        v.FILLERS,
        v.VERBS,
        v.TRICK_NAMES,
        v.TRICK_NAMES.values(),
        v.SHAPE_WORDS,
        v.WAIT_WORDS,
        v.THING_WORDS,
        _numbers.UNITS,
        _numbers.SPEED_UNITS,
        _numbers.NUMWORD.split("|"),
    )
    return frozenset(patterns | tables)


def _meaning(word: str) -> str:
    """Words that mean the same to the planner share this: a unit's kind and size ("metre",
    "meter"), or the word without a plural s ("degree", "degrees")."""
    kind = _numbers.UNITS.get(word)
    if kind is not None:
        return f"{kind}:{units.read(f'1 {word}', _numbers.UNIT_KINDS[kind])!r}"
    return word.removesuffix("s")


@functools.lru_cache(maxsize=1024)
def candidates(word: str) -> tuple[str, ...]:
    """The known words nearest to `word` within its limit, one per meaning (several when it is
    ambiguous)."""
    limit = _limit(word)
    best: list[str] = []
    best_distance = limit + 1
    for known in known_words():
        if known[0] != word[0] or len(known) < MIN_LENGTH:
            continue
        d = distance(word, known, limit)
        if d < best_distance:
            best, best_distance = [known], d
        elif d == best_distance and d <= limit:
            best.append(known)
    meanings: dict[str, str] = {}
    for known in sorted(best, key=lambda w: (-len(w), w)):  # "degrees" before "degree"
        meanings.setdefault(_meaning(known), known)
    return tuple(sorted(meanings.values()))


MAX_READINGS = 16  # combinations of ambiguous words tried; more is not a typo but noise


@dataclass
class Reading:
    """A clause with its misspellings read as known words, and what could not be read."""

    text: str
    written: str = ""  # the clause as it was written
    fixes: list[tuple[str, str]] = field(default_factory=list)  # (as written, read as)
    ambiguous: list[tuple[str, tuple[str, ...]]] = field(default_factory=list)
    unknown: list[str] = field(default_factory=list)  # neither known nor near a known word

    def alternatives(self) -> list[tuple[str, list[tuple[str, str]]]]:
        """Every way to read the ambiguous words (text, and what was read as what); the
        planner keeps a reading only if exactly one of them makes sense."""
        choices = [[(w, c) for c in cs] for w, cs in self.ambiguous]
        if not choices:
            return [(self.text, list(self.fixes))] if self.fixes else []
        found = []
        for combination in itertools.islice(itertools.product(*choices), MAX_READINGS):
            chosen = iter(c for _, c in combination)
            words = [next(chosen) if w in dict(self.ambiguous) else w for w in self.text.split()]
            found.append((" ".join(words), [*self.fixes, *combination]))
        return found

    def problems(self) -> str:
        """The words that stand in the way, for the user: "'rug' is not a word I know". A word
        read as another ("rug" as "run") is named too: the reading did not help."""
        parts = [f"'{w}' could be {' or '.join(repr(c) for c in cs)}" for w, cs in self.ambiguous]
        order = self.written.split()
        unknown = sorted({w for w, _ in self.fixes} | set(self.unknown), key=order.index)
        if unknown:
            listed = ", ".join(f"'{w}'" for w in unknown)
            verb = "is not a word" if len(unknown) == 1 else "are not words"
            parts.append(f"{listed} {verb} I know")
        return "; ".join(parts)


def read(clause: str) -> Reading:
    """Read each unknown word of a normalised clause as the one known word nearest to it."""
    known = known_words()
    words = []
    reading = Reading("", clause)
    for word in clause.split():
        if not word.isalpha() or word in known:
            words.append(word)
            continue
        found = candidates(word) if len(word) >= MIN_LENGTH else ()
        if len(found) == 1:
            reading.fixes.append((word, found[0]))
            words.append(found[0])
        else:
            if len(found) > 1:
                reading.ambiguous.append((word, found))
            else:
                reading.unknown.append(word)
            words.append(word)
    reading.text = " ".join(words)
    return reading
