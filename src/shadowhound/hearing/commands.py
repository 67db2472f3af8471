"""Spoken words that are not a mission: "stop", "halt", "e-stop" said on their own go to the
e-stop at once, before any planning. A sentence that only mentions stopping ("walk until I say
stop", "stop if you see a person") is a mission like any other."""

from __future__ import annotations

import re

_STOP = {"stop", "halt", "estop", "freeze", "abort"}
_WITH = {
    "e", "emergency", "please", "now", "right", "the", "robot", "dog", "it", "everything",
    "moving", "stop", "halt", "hey", "ok", "okay",
}  # fmt: skip
_WORDS = re.compile(r"[a-z]+")


def is_stop(transcript: str) -> bool:
    """Whether the words say only "stop" (with "please", "now", "emergency", a repeat ...)."""
    words = _WORDS.findall(transcript.lower().replace("e-stop", "estop"))
    return (
        bool(words)
        and any(w in _STOP for w in words)
        and all(w in _STOP or w in _WITH for w in words)
    )
