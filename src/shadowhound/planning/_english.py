"""Reading English for the offline planner: clauses, clean-up and tokens.

A request is split into clauses (`split_clauses`); each clause is lower-cased, stripped of
punctuation and politeness, and given its numbers in digits (`normalize`); what follows a verb is
cut into tokens: quantities, directions, speeds, fillers and other words (`scan`).

Everything here is plain text in, plain text (or tokens) out; what the words mean for the robot
is decided in `rules.py`.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from shadowhound import units
from shadowhound.planning._numbers import (
    NUM,
    NUMWORD,
    SPEED_UNITS,
    UNIT_ALT,
    UNIT_KINDS,
    UNITS,
    to_digits,
    to_float,
)
from shadowhound.planning._text import alternation, canon
from shadowhound.planning._vocabulary import ADVERBS, DIRECTIONS, FILLERS

# ---- splitting a request into clauses --------------------------------------------------------

_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f]")
_THOUSANDS = re.compile(r"(?<=[0-9]),(?=[0-9]{3}(?![0-9]))")
_KEEP_COMMA = re.compile(
    rf"((?:[0-9]|\b(?:{NUMWORD})\b)\s*),(?=\s*(?:-?\.?[0-9]|(?:minus|negative|{NUMWORD})\b))",
    re.I,
)
_KEEP_XY = re.compile(r"(\bx\s*[=:]?\s*[\w.-]+)\s*(?:,|\band\b)\s*(?=y\b)", re.I)
_KEEP_AND = re.compile(
    rf"\b(hundred|thousand|million|billion)\s+and\s+(?=(?:{NUMWORD})\b)"
    r"|\b(back|forth|forward|to)\s+and\s+(?=(?:forth|back|fro)\b)"
    r"|\b(go\s+ahead|try)\s+and\s+(?=\w)"
    r"|()\s+and\s+(?=(?:a\s+|an\s+|one\s+)?(?:half|quarter)\b)",
    re.I,
)
_SPLIT = re.compile(
    r"[,;!?\n&]+|\.(?![0-9])|\b(?:and|then|after\s+that|afterwards?|followed\s+by|after\s+which"
    r"|once\s+(?:done|finished)|when\s+(?:done|finished))\b",
    re.I,
)


def split_clauses(text: str) -> list[str]:
    """The clauses of a request in order, as the user wrote them (for labels)."""
    text = _THOUSANDS.sub("", _CONTROL.sub(" ", text))
    text = _KEEP_COMMA.sub("\\1\x01", text)
    text = _KEEP_XY.sub("\\1\x01 ", text)
    text = _KEEP_AND.sub(lambda m: f"{m.group(1) or m.group(2) or m.group(3) or ''} \x02 ", text)
    clauses = []
    for piece in _SPLIT.split(text):
        piece = piece.replace("\x01", ",").replace("\x02", "and").strip(" \t\r.,;:!?\"'")
        if piece:
            clauses.append(" ".join(piece.split()))
    return clauses


# ---- normalising one clause ------------------------------------------------------------------

_CHARMAP = str.maketrans(
    {"\u2019": "'", "\u2018": "'", "\u00b0": " deg ", "\u00d7": " x ", "\u2013": "-", "\u2014": "-",
     "\u2212": "-", "_": " "}
)  # fmt: skip
_CONTRACTIONS = {
    "what's": "what is", "where's": "where is", "how's": "how is", "it's": "it is",
    "that's": "that is", "there's": "there is", "let's": "let us", "i'd": "i would",
    "i'm": "i am", "you're": "you are", "don't": "do not", "dont": "do not",
    "doesn't": "does not", "can't": "can not", "won't": "will not", "what're": "what are",
}  # fmt: skip
_CONTRACTION = re.compile(rf"\b(?:{alternation(_CONTRACTIONS)})(?!\w)")
_PUNCT = re.compile(r"[^\w\s.\-/=:]|\.(?![0-9])|-(?![0-9.])")
_LEAD = re.compile(
    r"^(?:please|kindly|now|so|ok|okay|alright|all right|well|yo|hey there|hey|first of all"
    r"|first|firstly|next|finally|lastly|also|afterwards|just|go ahead and|would you mind"
    r"|(?:can|could|would|will) you(?: please)?|i (?:want|would like|need) you to"
    r"|you (?:should|can|must|need to|have to)|try to|try and|let us|robot|buddy|doggy|dog|boy|pup"
    r"|puppy|shadowhound|go2|dear)(?:\s+|$)"
)
_TRAIL = re.compile(
    r"\s+(?:please|now|thanks|thank you|for me|immediately|at once|right away|as well|too"
    r"|first|next)$"
)
# What a person calls the robot, said last ("sit down, dog"). The same words name things too
# ("go to the dog", "find the hot dog", "walk to the robot"): after an article or a possessive
# (and at most one word more) they are the thing, and stay.
_NAMES = r"robot|buddy|doggy|dog|boy|pup|puppy|shadowhound|go2"
_CALLED = re.compile(rf",\s*(?:{_NAMES})\s*[.!?]*\s*$")
_TRAIL_NAME = re.compile(rf"\s+(?:{_NAMES})$")
_THING = re.compile(
    r"\b(?:the|a|an|my|your|our|his|her|their|this|that|these|those|some|any)(?:\s+\S+)?$"
)
_PLEASE = re.compile(r"\bplease\b")


def normalize(clause: str, *, digits: bool = True) -> tuple[str, list[str]]:
    """Lower-case, punctuation-free clause with fillers stripped and numbers in digits (or, with
    `digits=False`, still in words, as spelling correction needs them)."""
    notes: list[str] = []
    text = clause.lower().translate(_CHARMAP)
    text = _CONTRACTION.sub(lambda m: _CONTRACTIONS[m.group(0)], text).replace("'", "")
    text = " ".join(_PUNCT.sub(" ", _CALLED.sub("", text)).split())
    for _ in range(8):
        before = text
        text = _TRAIL.sub("", _LEAD.sub("", _PLEASE.sub("", text).strip())).strip()
        called = _TRAIL_NAME.search(text)
        if called is not None and not _THING.search(text[: called.start()]):
            text = text[: called.start()]
        if text == before:
            break
    if " few" in f" {text}":
        notes.append(f"'a few' in '{clause}' taken as 3")
    text = to_digits(text) if digits else text
    return " ".join(text.split()), notes


# ---- tokens ------------------------------------------------------------------------------------

_SPEED_ALT = alternation(SPEED_UNITS)
_TOKEN = re.compile(
    rf"(?P<speed>at\s+(?:a\s+)?(?:speed\s+(?:of\s+)?)?(?P<sn>{NUM})\s*(?P<su>{_SPEED_ALT}))"
    # "around 2 meters" means roughly 2 m, not a turn; the word is dropped like a filler
    rf"|(?P<approx>(?:a)?round|about|approximately|roughly)(?=\s+-?\.?[0-9])"
    rf"|(?P<qty>{NUM})(?:\s*(?P<unit>{UNIT_ALT}))?(?![\w/])"
    rf"|(?P<dir>{alternation(DIRECTIONS)})(?!\w)"
    rf"|(?P<adv>{alternation(ADVERBS)})(?!\w)"
    rf"|(?P<fill>{alternation(FILLERS)})(?!\w)"
    r"|(?P<word>\S+)"
)


@dataclass(frozen=True)
class Token:
    """One meaningful piece of a clause: a quantity, a direction, a speed word or an odd word."""

    kind: str  # qty | speed | dir | adv | fill | word
    text: str
    value: float = 0.0
    unit: str = ""  # for qty: DISTANCE, ANGLE, TIME, or "" when the user gave no unit
    unit_name: str = ""  # the unit as written, e.g. "cm"


def quantity(number: str, unit: str | None) -> Token:
    value = to_float(number)
    if not unit:
        return Token("qty", number, value)
    name = canon(unit)
    kind = UNITS[name]
    value = _read(f"{number} {name}", UNIT_KINDS[kind])
    return Token("qty", f"{number} {unit}", value, kind, name)


def _read(text: str, kind: units.Kind) -> float:
    try:
        return units.read(text, kind)
    except units.UnitError:  # the number and unit are well-formed: only its size can be wrong
        raise ValueError(f"the quantity {text} is too large") from None


def scan(text: str) -> list[Token]:
    """Split a clause remainder into tokens. Raises ValueError for non-finite numbers."""
    tokens: list[Token] = []
    for m in _TOKEN.finditer(text):
        if m.group("speed"):
            speed = _read(f"{m.group('sn')} {canon(m.group('su'))}", units.SPEED)
            tokens.append(Token("speed", m.group(0), speed))
        elif m.group("qty"):
            tokens.append(quantity(m.group("qty"), m.group("unit")))
        elif m.group("dir"):
            tokens.append(Token("dir", DIRECTIONS[canon(m.group("dir"))]))
        elif m.group("adv"):
            tokens.append(Token("adv", m.group("adv"), ADVERBS[canon(m.group("adv"))]))
        elif m.group("word"):
            tokens.append(Token("word", m.group("word")))
    return tokens
