"""Numbers for the offline planner: the units a sentence may use, and numbers in words.

`to_digits` rewrites "one and a half meters" or "a quarter turn" as "1.5 meters" or "90 deg", so
the rest of the planner only ever sees numbers in digits.
"""

from __future__ import annotations

import math
import re

from shadowhound import units
from shadowhound.planning._text import alternation, words
from shadowhound.units import format_number

DISTANCE = "distance"
ANGLE = "angle"
TIME = "time"

NUM = r"-?(?:[0-9]+(?:\.[0-9]+)?|\.[0-9]+)"

# The planner's kinds of quantity, in the units `shadowhound.units` reads them in.
UNIT_KINDS = {DISTANCE: units.LENGTH, ANGLE: units.ANGLE, TIME: units.DURATION}
# "walk 2 in the kitchen": in a sentence "in" is a preposition far more often than inches.
_NOT_IN_SENTENCES = {"in"}

# Unit name -> kind, for the units a sentence may use. Converting them is `shadowhound.units`'
# job (see `_english.quantity`), the same conversion every other path uses.
UNITS: dict[str, str] = {
    name: planner_kind
    for planner_kind, kind in UNIT_KINDS.items()
    for name in units.unit_names(kind)
    if name not in _NOT_IN_SENTENCES
}

# Speed units a sentence may use ("at 2 km/h"), also converted by `shadowhound.units`.
SPEED_UNITS = words(
    "m/s|mps|meters per second|metres per second|meter per second|metre per second|cm/s"
    "|km/h|kph|kmh|km per hour|kilometers per hour|kilometres per hour|mph|miles per hour",
    "|",
)

UNIT_ALT = alternation(UNITS)
QTY = re.compile(rf"({NUM})\s*({UNIT_ALT})?(?![\w/])")


def to_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"the number {text[:20]}... is too large")
    return value


# ---- numbers written in words ----------------------------------------------------------------

_SMALL = words(
    "zero one two three four five six seven eight nine ten eleven twelve thirteen fourteen"
    " fifteen sixteen seventeen eighteen nineteen"
)
_TENS = words("twenty thirty forty fifty sixty seventy eighty ninety")
_VALUES = {w: i for i, w in enumerate(_SMALL)} | {w: 20 + 10 * i for i, w in enumerate(_TENS)}
_SCALES = {"hundred": 100, "thousand": 1000, "million": 1_000_000, "billion": 1_000_000_000}
NUMWORD = alternation([*_VALUES, *_SCALES])
_DIGITWORD = alternation(_SMALL[:10])

_TURN_WORDS = r"(?:turn|rotation|revolution|circle|spin)(?!s)\b"
_ONE = r"\b(?:a\s+|one\s+|1\s+)?"
_PHRASES = [
    (re.compile(rf"{_ONE}three\s+quarters?\s+(?:of\s+a\s+)?{_TURN_WORDS}"), "270 deg"),
    (re.compile(rf"{_ONE}quarter\s+(?:of\s+a\s+)?{_TURN_WORDS}"), "90 deg"),
    (re.compile(rf"{_ONE}half\s+(?:a\s+|of\s+a\s+)?{_TURN_WORDS}"), "180 deg"),
    (re.compile(rf"{_ONE}(?:full|complete|whole|entire)\s+{_TURN_WORDS}"), "360 deg"),
    (re.compile(r"\ball\s+the\s+way\s+(?:a)?round\b|\bin\s+a\s+(?:full\s+)?circle\b"), "360 deg"),
    (re.compile(r"\ba\s+(hundred|thousand|million|billion)\b"), r"one \1"),
    (re.compile(r"\ba\s+dozen\b"), "12"),
    (re.compile(r"\b(?:a\s+)?(?:couple|pair)(?:\s+of)?\b"), "2"),
    (re.compile(r"\b(?:a\s+)?few\b"), "3"),
]
_RUN = re.compile(
    rf"\b(?:{NUMWORD})\b(?:(?:\s+|\s+and\s+)(?:{NUMWORD})\b)*"
    rf"(?:\s+point(?:\s+(?:{_DIGITWORD})\b)+)?|\bpoint(?:\s+(?:{_DIGITWORD})\b)+"
)
_LONG_UNITS = alternation(
    w for w in UNITS if len(w) > 2 and UNITS[w][0] != ANGLE or w.startswith(("deg", "rad"))
)
_AFTER = [
    (re.compile(r"\b(?:minus|negative)\s+(?=\.?[0-9])"), "-"),
    (re.compile(r"(?<![\w.])([0-9]+)\s+([0-9]+)/([0-9]+)\b"), None),
    (re.compile(r"(?<![\w./])([0-9]+)/([1-9][0-9]*)\b"), None),
    (re.compile(rf"\b(?<!half\s)(?<!quarter\s)(?<!of\s)(?:a|an|another)\s+(?=(?:{_LONG_UNITS})\b)"),
     "1 "),
    (re.compile(rf"(?<![0-9.])({NUM})\s+(?:({_LONG_UNITS})\s+)?and\s+(?:a|an|one)\s+"
                r"(half|quarter)\b"), None),
    (re.compile(rf"\b(?:a\s+|one\s+|1\s+)?half\s+(?:of\s+)?(?:a\s+|an\s+)?(?=(?:{_LONG_UNITS})\b)"),
     "0.5 "),
    (re.compile(rf"\b(?:a\s+|one\s+|1\s+)?quarter\s+(?:of\s+)?(?:a\s+|an\s+)?(?=(?:{_LONG_UNITS})\b)"),
     "0.25 "),
    (re.compile(r"([0-9.])\s+(?:full|complete|whole)\s+(?=(?:turn|rotation|revolution)s?\b)"),
     r"\1 "),
    (re.compile(rf"(?<![0-9.])({NUM})\s*(?:x|by|\*)\s*(?={NUM})"), r"\1 by "),
]  # fmt: skip


def _words_to_numbers(m: re.Match[str]) -> str:
    words = m.group(0).split()
    decimals = ""
    if "point" in words:
        at = words.index("point")
        decimals = "".join(str(_VALUES[w]) for w in words[at + 1 :])
        words = words[:at]
    groups: list[float] = []
    total = current = 0
    top = 0  # the largest scale in `total`
    last = ""
    for word in words:
        if word == "and":
            continue
        if word in _SCALES:
            scale = _SCALES[word]
            if scale == 100:
                current = (current or 1) * 100
            elif scale > top:  # "one thousand million": the million scales all that came before
                total, current, top = (total + current or 1) * scale, 0, scale
            else:  # "two million three thousand"
                total, current = total + (current or 1) * scale, 0
            last = "scale"
            continue
        value = _VALUES[word]
        kind = "tens" if value >= 20 else "small"
        if last == "small" or (last == "tens" and (kind == "tens" or value >= 10)):
            groups.append(total + current)  # "two one" is two numbers, "twenty one" is one
            total = current = 0
        current += value
        last = kind
    numbers = [*groups, total + current] if last else groups
    text = [format_number(n) for n in numbers]
    if decimals:
        whole = text.pop() if text else "0"
        text.append(f"{whole}.{decimals}")
    return " ".join(text)


def _after(m: re.Match[str]) -> str:
    groups = m.groups()
    if len(groups) == 3 and groups[2] in ("half", "quarter"):
        value = float(groups[0]) + (0.5 if groups[2] == "half" else 0.25)
        return f"{format_number(value)} {groups[1] or ''}".rstrip()
    if len(groups) == 3:
        return format_number(int(groups[0]) + int(groups[1]) / int(groups[2]))
    return format_number(int(groups[0]) / int(groups[1]))


def to_digits(text: str) -> str:
    """`text` (normalised) with turn phrases, number words and fractions written as digits."""
    for pattern, replacement in _PHRASES:
        text = pattern.sub(replacement, text)
    text = _RUN.sub(_words_to_numbers, text)
    for pattern, repl in _AFTER:
        text = pattern.sub(_after if repl is None else repl, text)
    return text
