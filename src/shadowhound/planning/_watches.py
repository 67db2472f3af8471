"""How the offline planner reads conditions it can watch: "walk forward until you see the red
ball", "walk forward 5 meters unless something is in the way", "... and stop if you see a
person", "... until the battery is below 30 percent".

A condition becomes a `plan.Watch` on the steps it governs; the runtime evaluates it. A
condition that is not one of these kinds is not understood (NotUnderstood names it): the
planner never drops a condition a person stated.
"""

from __future__ import annotations

import re
from collections.abc import Iterator

from ..errors import NotUnderstood
from ..plan import Watch

IN_THE_WAY_METRES = 1.0  # how far ahead of the body "in the way" looks unless told

# ACTION until|unless|stop if CONDITION (on a normalised clause)
WATCHED = re.compile(
    r"^(?P<action>.+?)\s+(?P<when>until|till|unless|except\s+if|while|as\s+long\s+as"
    r"|(?:and\s+|but\s+)?stop\s+if"
    r"|stopping\s+if|(?:and\s+|but\s+)?stop\s+(?:when|once|as\s+soon\s+as))\s+(?P<cond>.+)$"
)
# a clause of its own that stops what came before it: "(and) stop if you see a person"
STOP_IF = re.compile(
    r"^(?:and\s+|but\s+|then\s+)?(?:stop|halt|freeze)(?:\s+(?:moving|walking|there))?\s+"
    r"(?:if|when|once|as\s+soon\s+as|whenever|in\s+case)\s+(?P<cond>.+)$"
)
# "if CONDITION (then) ACTION" / "if CONDITION" (the action in the clauses after it)
IF = re.compile(r"^(?:if|in\s+case|should)\s+(?P<rest>.+)$")
# "when CONDITION (,) ACTION": a branch like "if" when what follows is a condition it can
# watch ("when the battery is below 20% go to the dock"); else "when" is left to the clause
# ("when you get there say hello": the rules say why they do not plan it)
WHEN = re.compile(r"^when\s+(?P<rest>.+)$")
# "otherwise ACTION" / "else ACTION" / "if not, ACTION"
OTHERWISE = re.compile(r"^(?:otherwise|else|or\s+else|if\s+not)(?:\s+(?P<rest>.+))?$")
_DISTANCE = r"(?P<d>\d+(?:\.\d+)?)\s*(?:m|meters?|metres?)"
_SEEN = re.compile(
    r"^(?:(?:you|u|we|i)\s+)?(?:can\s+|do\s+)?(?:see|spot|find|notice|detect|sight|spy|catch\s+"
    r"sight\s+of)\s+(?:a|an|the|some|any)?\s*(?P<name>.+?)(?:\s+within\s+" + _DISTANCE + r")?"
    r"(?:\s+(?:ahead|in\s+front(?:\s+of\s+you)?))?$"
    r"|^(?:a|an|the)?\s*(?P<name2>.+?)\s+(?:is|comes|appears|gets)\s+(?:in\s+view|in\s+sight"
    r"|visible|into\s+view|seen)$"
)
_SOMETHING = (
    r"(?:something|anything|somebody|someone|anybody|anyone|a\s+person|people|a\s+human"
    r"|an?\s+obstacle|obstacles|a\s+thing|things|an\s+object|objects)"
)
_IN_THE_WAY = re.compile(
    r"^(?:there\s+(?:is|are)\s+)?" + _SOMETHING + r"\s+(?:is\s+|are\s+|gets\s+|comes\s+"
    r"|stands\s+|appears\s+|steps\s+|shows\s+up\s+|turns\s+up\s+)?"
    r"(?:in\s+(?:the|your|my|its|our)\s+(?:way|path)|blocking\s+(?:the|your|my)\s+(?:way|path)"
    r"|blocks\s+(?:the|your|my)\s+(?:way|path)"
    r"|(?:right\s+|directly\s+|just\s+)?in\s+front(?:\s+of\s+(?:you|me|the\s+robot|it))?"
    r"|(?:right\s+|directly\s+|close\s+)?ahead(?:\s+of\s+(?:you|the\s+robot|it))?"
    r"|gets\s+in\s+the\s+way)(?:\s+within\s+" + _DISTANCE + r")?$"
    r"|^(?:the\s+|your\s+)?(?:way|path)\s+is\s+(?:blocked|not\s+clear|obstructed)$"
    r"|^(?:you\s+)?(?:are|get)\s+(?:blocked|stuck)$"
)
_OPERATOR = re.compile(
    r"^(?:i|we|you\s+are|someone|somebody|anyone)\s+(?:say|says|tell\s+you|tells\s+you|told\s+you"
    r"|ask\s+you|asks\s+you)(?:\s+to)?\s+(?:stop|halt|so|otherwise|enough)$"
    r"|^(?:you\s+are\s+|you\s+get\s+)?(?:told|asked)\s+to\s+stop$|^(?:i|we)\s+stop\s+you$"
)
_BATTERY_ABOVE = re.compile(
    r"^(?:the\s+|your\s+)?battery(?:\s+level)?\s+(?:is\s+|stays\s+|remains\s+)?"
    r"(?:above|over|more\s+than|higher\s+than|at\s+least)\s+(?P<p>\d+(?:\.\d+)?)(?:\s*percent)?$"
)
# "keep patrolling", "patrol continuously": as long as the mission's limits allow
KEEP_GOING = re.compile(
    r"\b(?:keep|keeps|continue|continuously|constantly|forever|nonstop|non\s+stop|endlessly"
    r"|indefinitely|all\s+(?:day|night)|on\s+and\s+on|again\s+and\s+again)\b"
)
# "while CONDITION (,) ACTION" / "as long as CONDITION ACTION"
WHILE = re.compile(r"^(?:while|as\s+long\s+as|so\s+long\s+as)\s+(?P<rest>.+)$")
_BATTERY = re.compile(
    r"^(?:the\s+|your\s+)?battery(?:\s+level)?\s+(?:is\s+|gets\s+|goes\s+|drops\s+|falls\s+)?"
    r"(?:below|under|less\s+than|lower\s+than|beneath)\s+(?P<p>\d+(?:\.\d+)?)(?:\s*percent)?$"
)
_PEOPLE = {"person", "people", "someone", "somebody", "anyone", "anybody", "human", "man", "woman"}
CAN_WATCH = (
    "I can watch until or unless something named is seen ('until you see the red ball'), "
    "something is in the way ('unless something is in the way'), or the battery is below a "
    "percent"
)


def watch_of(when: str, condition: str) -> Watch:
    """The watch `condition` (normalised words) states; NotUnderstood when it cannot be one."""
    when = " ".join(when.split())
    kind = "until" if when in ("until", "till") else "unless"
    words = re.sub(r"\bi\b", "I", f"{when} {condition}")
    cond = condition.strip()
    if when in ("while", "as long as", "so long as"):  # "while X" is "until not X"
        above = _BATTERY_ABOVE.match(cond)
        if above:
            percent = float(above["p"])
            said = f"{when} the battery is above {percent:g}%"
            return Watch("until", "battery_below", percent=percent, words=said)
        raise NotUnderstood(
            f"I do not plan around conditions ('{when}') such as '{condition}': I can go on "
            "while the battery is above a percent"
        )
    if _OPERATOR.match(cond):
        return Watch(kind, "operator_stop", words=words)
    m = _IN_THE_WAY.match(cond)
    if m:
        within = float(m["d"]) if m["d"] else IN_THE_WAY_METRES
        return Watch(kind, "in_the_way", within=within, words=words)
    m = _SEEN.match(cond)
    if m:
        # "see the" is not a thing called "the": a name is more than its article
        name = re.sub(r"^(?:a|an|the|some|any|this|that)\b\s*", "", (m["name"] or m["name2"] or ""))
        name = name.strip()
        if name in _PEOPLE:
            name = "person"
        near = float(m["d"]) if m["d"] else None
        if name and not re.search(r"\b(?:if|unless|until|while|and|or|not)\b", name):
            return Watch(kind, "seen", name=name, within=near, words=words)
    m = _BATTERY.match(cond)
    if m:
        percent = float(m["p"])
        said = f"{' '.join(when.split())} the battery is below {percent:g}%"
        return Watch(kind, "battery_below", percent=percent, words=said)
    raise NotUnderstood(
        f"I do not plan around conditions ('{' '.join(when.split())}') such as '{condition}': "
        f"{CAN_WATCH}"
    )


def split_condition(rest: str) -> Iterator[tuple[Watch, str]]:
    """Ways to read "the battery is below 30 go to the dock" as a condition and what to do:
    (the guard, "go to the dock"), the shortest condition first; the action (after a "then")
    may be empty (it is in the clauses that follow). The caller takes the first whose action
    it can plan."""
    words = rest.split()
    for k in range(2, len(words) + 1):
        head, tail = " ".join(words[:k]), " ".join(words[k:])
        try:
            watch = watch_of("if", head)
        except NotUnderstood:
            continue
        tail = re.sub(r"^(?:then|do)\s+", "", tail)
        said = watch.words.replace("if ", "if ", 1) if watch.kind == "battery_below" else ""
        yield (
            Watch("if", watch.kind, watch.name, watch.within, watch.percent, said or f"if {head}"),
            tail,
        )


# "follow the person", "follow me at 2 meters", "keep following the red ball for 30 seconds"
FOLLOW = re.compile(
    r"^(?:please\s+)?(?:keep\s+|continue\s+|start\s+)?(?:follow(?:ing)?|track(?:ing)?(?!\s+down)"
    r"|tail(?:ing)?"
    r"|shadow(?:ing)?|come\s+(?:along\s+)?with|walk\s+with|stay\s+with|stick\s+with)\s+"
    r"(?:(?P<me>me|us)|(?:the|that|this|a|an|my)?\s*(?P<name>[a-z][a-z ]*?))"
    r"(?:\s+(?:at|from)\s+(?:a\s+distance\s+of\s+)?(?P<d>\d+(?:\.\d+)?)\s*(?:m|meters?|metres?)"
    r"(?:\s+(?:away|behind|back|distance))?)?"
    r"(?:\s+for\s+(?P<t>\d+(?:\.\d+)?)\s*(?P<unit>s|secs?|seconds?|mins?|minutes?))?"
    r"(?:\s+around)?$"
)
