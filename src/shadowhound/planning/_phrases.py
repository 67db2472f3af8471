"""Phrase patterns of the offline planner: regexes that recognise each kind of clause.

They are matched against clauses already normalised by `_english.normalize` (lower case, numbers
in digits), e.g. a stop, a wait, a posture, a go-to, a patrol, a move, a question, a repeat count.
What a match means for the robot is decided in `rules.py`.
"""

from __future__ import annotations

import re

from shadowhound.planning._numbers import NUM, UNIT_ALT, to_float
from shadowhound.planning._text import alternation
from shadowhound.planning._vocabulary import ADVERBS, DIRECTIONS, VERBS

TRICK_PREFIX = re.compile(
    r"^(?:do|perform|show(?:\s+(?:me|us))?|make|give(?:\s+(?:me|us))?|try|execute|strike|take"
    r"|bust|pull\s+off|let\s+me\s+see|have|go\s+for)\s+"
)
TRICK_STOPWORDS = re.compile(r"\b(?:a|an|the|your|my|some|this|that)\b")
TRICK_TAIL = re.compile(
    r"\s+(?:trick|move|for\s+(?:me|us)|at\s+(?:me|us)|to\s+(?:me|us|everyone|everybody)"
    r"|for\s+camera|now)$"
)
GREET = re.compile(r"^(?:greet|wave\s+(?:at|to))\b")

STOP = re.compile(
    r"^(?:emergency\s+)?(?:stop|halt|freeze|cease|abort|whoa|estop|e\s+stop)(?:\s+(?:moving"
    r"|walking|running|motion|everything|it|there|right\s+there|all\s+motion|here))*$"
    r"|^(?:stand|stay|hold|keep)\s+still$|^(?:do\s+not|never)\s+move$|^hold\s+it$"
    r"|^(?:that\s+is\s+)?enough$"
)
CONDITION = re.compile(
    r"\b(?:if|unless|until|till|whenever|when|while|as\s+soon\s+as|as\s+long\s+as|in\s+case"
    r"|once\s+(?:you|i|we|it|they|the)|provided)\b"
)
NEGATION = re.compile(r"\b(?:do\s+not|does\s+not|never|not|no\s+longer|can\s+not|will\s+not)\b")
WAIT = re.compile(
    r"^(?:wait|pause|hold\s+on|hold\s+(?:your\s+)?position|hold\s+it|hold|hang\s+on|hang\s+tight"
    r"|stay\s+put|stay|sleep|rest|remain|sit\s+tight|stand\s+still|stay\s+still|hold\s+still"
    r"|keep\s+still|freeze|take\s+a\s+(?:break|breather|rest)|delay|idle|stand\s+by|standby"
    r"|chill|do\s+nothing)(?:\s+(?P<rest>.+))?$"
)
POSTURE = re.compile(
    r"^(?:(?P<lie>(?:lie|lay)(?:\s+(?:yourself\s+)?down)?(?:\s+flat)?|get\s+down|down"
    r"|go\s+(?:to\s+)?sleep|take\s+a\s+nap|nap|stand\s+down|crouch"
    r"|lie\s+on\s+(?:the\s+)?(?:floor|ground))"
    r"|(?P<sit>sit(?:\s+(?:back\s+)?down)?|take\s+a\s+seat|have\s+a\s+seat|be\s+seated)"
    r"|(?P<stand>stand(?:\s+(?:back\s+)?up)?|get\s+(?:back\s+)?up|rise(?:\s+up)?|stand\s+tall"
    r"|stand\s+upright|get\s+on\s+(?:your\s+)?feet|on\s+(?:your\s+)?feet|up|wake\s+up))"
    r"(?:\s+(?P<rest>.+))?$"
)
# What a posture may add that changes nothing: where (the spot it is on) and how.
POSTURE_EXTRA = re.compile(
    r"\b(?:on\s+(?:the\s+|your\s+)?(?:floor|ground)|(?:right\s+)?(?:here|there)|right\s+now|now"
    r"|where\s+you\s+are|straight|upright|nicely|calmly|quietly|properly|for\s+(?:me|us))\b"
)

GO = (
    r"go|come|head|walk|run|jog|trot|get|travel|hurry|drive|proceed|move|navigate|march"
    r"|make\s+your\s+way|find\s+your\s+way"
)
GOTO = re.compile(
    rf"^(?:(?P<ret>return|visit|approach|enter)|(?P<verb>{GO}))(?P<back>\s+back)?"
    r"(?:\s+(?:over|on|up|down|straight|directly|right|all\s+the\s+way))*"
    r"(?:\s+(?P<prep>to|towards|toward|into|in\s+to|up\s+to|over\s+to))?(?:\s+(?P<target>.+))?$"
)
# Requests to go to a thing found by name: "find the blue box", "bring me to the fridge".
FIND = re.compile(
    r"^(?:(?:go\s+(?:and\s+)?|please\s+)?(?:find|locate|seek|search\s+for|look\s+for"
    r"|hunt\s+for|track\s+down)"
    r"|(?:bring|take|lead|guide|escort|show)\s+(?:me|us)\s+(?:the\s+way\s+)?"
    r"(?:to|towards|toward|over\s+to|up\s+to))\s+(?P<target>.+)$"
)
HOME = re.compile(r"^(?:the\s+|your\s+)?(?:home(?:\s+base)?|origin)$")
START = re.compile(
    r"^(?:the\s+|your\s+)?(?:start|starting\s+(?:point|position|location|spot|place|pose|line)"
    r"|start\s+(?:point|position|location|spot)|beginning|initial\s+(?:position|point|location)"
    r"|original\s+(?:position|spot|location|place)|here|me|us"
    r"|where\s+(?:you|we)\s+(?:started|began|were|came\s+from|start)(?:\s+from)?)$"
)
POSITION_WORDS = r"(?:the\s+)?(?:position|point|coordinates?|coords?|location|spot|waypoint|xy)"
COORDS = re.compile(
    rf"^(?:{POSITION_WORDS}\s*)?(?:x\s*[=:]?\s*)?(?P<x>{NUM})\s*(?P<xu>{UNIT_ALT})?"
    rf"\s+(?:y\s*[=:]?\s*)?(?P<y>{NUM})\s*(?P<yu>{UNIT_ALT})?$"
)
POSITION_ONLY = re.compile(rf"^{POSITION_WORDS}\b")

ARTICLES = re.compile(r"^(?:my|our|your)\s+|\b(?:the|a|an)\b")

ROTATE_PREFIXES = [
    (re.compile(r"^(?:do\s+(?:a|an)\s+)?(?:about\s+face|about\s+turn|u\s+turn|uturn)\b"),
     "turn around"),
    (re.compile(r"^(?:make|take|hang|do|perform|execute|complete|pull)\s+(?:a\s+|an\s+)?"
                r"(left|right)(?:\s+turn)?\b"), r"turn \1"),
    (re.compile(r"^(?:make|do|perform|execute|complete|take)\s+(?:a\s+|an\s+)?(.*?)\s*\b"
                r"(turn|spin|pivot)s?\b"), r"\2 \1"),
    (re.compile(r"^(?:make|do|perform|execute|complete|take)\s+(?:a\s+|an\s+)?(.*?)\s*\b"
                r"rotations?\b"), r"rotate \1"),
    (re.compile(rf"^(?:make|do|perform|execute|complete)\s+(?:a\s+|an\s+)?(?={NUM}"
                r"(?:\s*deg\w*)?(?:\s|$))"), "turn "),
]  # fmt: skip

MOTION = re.compile(rf"^(?P<verb>{alternation(VERBS)})(?!\w)\s*(?P<rest>.*)$")
LEAD_ADVERB = re.compile(rf"^(?P<adv>{alternation(ADVERBS)})\s+")

PATROL = re.compile(r"\b(?:patrol\w*|perimeter|laps?|circuits?)\b")
LAPS = re.compile(rf"(?<![0-9.])({NUM})\s+(?:patrol\s+)?(?:laps?|rounds?|circuits?|loops?)\b")
SHAPE = re.compile(r"\b(triangle|square|rectangle|pentagon|hexagon|octagon)s?\b")

PLACE = re.compile(r"^[^\W\d_][\w ]{0,60}$")
NOT_PLACES = frozenset([*DIRECTIONS, "front", "side", "rear", "here", "there", "me", "you"])

STATUS = re.compile(
    r"\b(?:battery|batteries|status|charge|charged|power\s+level|health|healthy|diagnostics?"
    r"|how\s+are\s+you|how\s+you\s+are|where\s+are\s+you|where\s+you\s+are|your\s+(?:position"
    r"|location|pose|state|condition|coordinates|heading)|are\s+you\s+(?:ok|okay|alright"
    r"|all\s+right|fine)|sitrep|systems?\s+check)\b"
)
# Turning to face a thing: "face the blue box", "turn towards the chair", "look at the person".
FACE = re.compile(
    r"^(?:(?:turn|rotate|spin|pivot)(?:\s+(?:yourself|(?:a)?round))?\s+(?:to\s+face|towards?"
    r"|to\s+look\s+(?:at|towards?)|to|so\s+(?:that\s+)?you(?:\s+are|re)?\s+fac(?:e|ing))"
    r"|(?:turn|point)\s+(?:your\s+)?(?:head|camera|nose|face|eyes)\s+(?:to|towards?|at)"
    r"|face|look\s+(?:at|towards?)|point\s+(?:yourself\s+)?(?:at|towards?)"
    r"|(?:stare|gaze)\s+at|orient\s+(?:yourself\s+)?(?:to|towards?))\s+(?P<target>.+)$"
)
# What "look at ..." may name that is no thing to face: the view itself.
VIEW_WORDS = frozenset(
    {"view", "scene", "surroundings", "room", "area", "things", "stuff", "everything",
     "it", "this", "that", "what", "whats", "around", "me", "us", "camera", "picture"}
)  # fmt: skip
# Questions about the robot's own travel: "how far have you walked?", "how long have you been
# walking?", "what is your odometer?".
TRAVEL = re.compile(
    r"\bhow\s+(?:far|much\s+distance|many\s+(?:metres|meters|m))\b"
    r"|\bhow\s+(?:long|much\s+time)\s+(?:have\s+|did\s+|were\s+|are\s+)?(?:you\s+)?(?:been\s+)?"
    r"(?:walk|mov|travel|run|roam|wander|on\s+(?:the\s+)?move)\w*"
    r"|\bodometer\b|\bdistance\s+(?:travel+ed|walked|covered|so\s+far)"
    r"|\b(?:travel+ed|walked|covered)\s+so\s+far\b"
)
REPORT = re.compile(r"^(?:report(?:\s+in|\s+back)?|give\s+(?:me\s+)?(?:a\s+)?report|check\s+in)$")
LOOK_AROUND = re.compile(
    r"^(?:(?:take|have)\s+a\s+look|look|scan|glance|peek|search|check|survey)"
    r"(?:\s+all)?\s+(?:(?:a)?round|360\s+deg)\b"
    r"|^(?:scan|survey|sweep)\s+(?:the\s+)?(?:room|area|surroundings|environment|place|scene)\b"
    r"|\blook\s+in\s+(?:every|all)\s+directions?\b|^(?:do\s+a\s+)?(?:360\s+deg\s+)?(?:scan|sweep)$"
)
DESCRIBE = re.compile(
    r"\b(?:see|seeing|describe|surroundings|in\s+front|ahead|look|looking|view|camera|visible"
    r"|notice|observe|spot|picture|photo|snapshot|obstacles?|is\s+there|are\s+there|anything"
    r"|anyone|anybody|someone|somebody|nearby|what\s+is\s+(?:there|around|near))\b"
)

TIMES = re.compile(
    rf"(?:^|\s+)(?:(?P<word>once|twice|thrice)|(?P<n>{NUM})\s*(?P<more>more\s+)?times?"
    r"|x\s?(?P<x1>[0-9]+)|(?P<x2>[0-9]+)\s?x|(?P<again>again|1\s+more\s+time))"
    r"(?:\s+(?:in\s+a\s+row|over|more|again))?$"
)
REPEAT_ALL = re.compile(
    r"^(?:(?:repeat|redo)(?:\s+(?:it|that|this|them|those|these|everything|all|all\s+of\s+"
    r"(?:that|this|it)|all\s+that|the\s+(?:same|whole\s+thing|above|sequence|pattern|steps"
    r"|route|path|routine|process)|(?:that|this)\s+(?:sequence|pattern|routine)))?"
    r"|do\s+(?:it|that|this|the\s+same(?:\s+thing)?|everything|all\s+(?:of\s+)?that"
    r"|the\s+whole\s+thing))$"
)
WORD_TIMES = {"once": 1, "twice": 2, "thrice": 3}


def repetition(text: str) -> tuple[str, int, str]:
    """Strip a trailing repeat count: (rest, count, how) where how is ""|times|more|again."""
    m = TIMES.search(text)
    if m is None:
        return text, 1, ""
    if m["word"]:
        count, how = WORD_TIMES[m["word"]], "again" if m["word"] == "once" else "times"
    elif m["again"]:
        count, how = 1, "again"
    else:
        raw = m["n"] or m["x1"] or m["x2"]
        value = to_float(raw)
        if value != int(value) or value < 1:
            raise ValueError(f"'{raw}' is not a whole number of times")
        count, how = int(value), "more" if m["more"] else "times"
    return text[: m.start()].strip(), count, how
