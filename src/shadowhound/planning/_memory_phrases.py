"""Phrases about memory: teach or forget a place, list places, teach a fact, recall the past.

Matched on the clause as the person wrote it (lower-cased), so place names and facts keep
their words; these run before every other kind of clause.
"""

from __future__ import annotations

import re

from shadowhound.plan import SkillCall

_HERE = (
    r"(?:this|the\s+current|your\s+current|current|our|my)\s+(?:spot|place|location|"
    r"position|point|pose|room)|where\s+(?:you\s+are|we\s+are|i\s+am)(?:\s+now)?|here"
)
_NAME = r"(?:the\s+|a\s+|an\s+|my\s+|our\s+)?(?P<name>[a-z][a-z' -]{0,58}[a-z])"
REMEMBER_PLACE = [
    re.compile(p)
    for p in (
        rf"^(?:remember|save|mark|store|memori[sz]e|record|tag|label)\s+(?:{_HERE})\s+as\s+{_NAME}$",
        rf"^(?:call|name)\s+(?:{_HERE})\s+{_NAME}$",
        rf"^(?:this|here)\s+(?:spot\s+|place\s+|location\s+)?is\s+{_NAME}$",
    )
]
FORGET_PLACE = re.compile(
    rf"^(?:forget|delete|remove|erase)\s+(?:the\s+)?(?:place|spot|location)?\s*"
    rf"(?:called|named)?\s*{_NAME}$"
)
FACT = re.compile(r"^(?:remember|note|keep\s+in\s+mind|learn|memori[sz]e)\s+that\s+(?P<fact>.+)$")
LIST_PLACES = re.compile(
    r"^(?:list|show|name|tell\s+me)\s+(?:me\s+)?(?:the\s+|all\s+|your\s+)*(?:known\s+|saved\s+)?"
    r"(?:places|locations|spots)\b|^(?:what|which)\s+places\s+do\s+you\s+know\b"
)
RECALL = re.compile(
    r"^(?:what|who|where)\s+(?:did|have|had)\s+you\s+(?:see|seen|find|found|notice|noticed|"
    r"meet|met|do|done)\b|^what\s+do\s+you\s+(?:remember|know)\s+about\b|^do\s+you\s+remember\b"
    r"|^where\s+(?:is|are)\s+(?:the\s+|my\s+|our\s+)?(?!you\b)[a-z]+|^what\s+happened\b"
    r"|^recall\b"
)
_ENDING = re.compile(r"[\s.!?]+$")
_FILLER = re.compile(r"^(?:please\s+|can\s+you\s+|could\s+you\s+|would\s+you\s+|now\s+)+")


def memory_steps(label: str) -> list[SkillCall] | None:
    """Steps for a memory clause, or None if the clause is about something else."""
    raw = " ".join(label.strip().lower().split())
    text = _FILLER.sub("", _ENDING.sub("", raw))
    if FACT.match(text):
        fact = _ENDING.sub("", " ".join(label.strip().split()))
        fact = fact[fact.lower().index(" that ") + 6 :] if " that " in fact.lower() else fact
        return [SkillCall("memory.note", {"text": fact}, label)]
    for pattern in REMEMBER_PLACE:
        if m := pattern.match(text):
            return [SkillCall("places.remember", {"name": m["name"].strip()}, label)]
    if (m := FORGET_PLACE.match(text)) and m["name"] not in ("that", "it", "everything"):
        return [SkillCall("places.forget", {"name": m["name"].strip()}, label)]
    if LIST_PLACES.match(text):
        return [SkillCall("places.list", {}, label)]
    if RECALL.match(text):
        return [SkillCall("memory.recall", {"query": label.strip()}, label)]
    return None
