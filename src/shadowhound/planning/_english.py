"""English helpers for the offline planner: clause splitting, clean-up, numbers, units, tokens.

Everything here is plain text in, plain text (or tokens) out; what the words mean for the robot
is decided in `rules.py`.
"""

from __future__ import annotations

import math
import re
from collections.abc import Iterable
from dataclasses import dataclass

DISTANCE = "distance"
ANGLE = "angle"
TIME = "time"

NUM = r"-?(?:[0-9]+(?:\.[0-9]+)?|\.[0-9]+)"


def words(text: str, sep: str | None = None) -> list[str]:
    """Split a word list written as one string; tables stay short and readable that way."""
    return text.split(sep)


# Unit name -> (kind, multiplier, divisor). Dividing separately keeps "50 cm" exactly 0.5 m.
UNITS: dict[str, tuple[str, float, float]] = {}


def _units(kind: str, mul: float, div: float, names: str) -> None:
    for name in names.split():
        UNITS[name] = (kind, mul, div)


_units(DISTANCE, 1.0, 1.0, "m meter meters metre metres mtr mtrs")
_units(DISTANCE, 1.0, 100.0, "cm centimeter centimeters centimetre centimetres")
_units(DISTANCE, 1.0, 1000.0, "mm millimeter millimeters millimetre millimetres")
_units(DISTANCE, 1000.0, 1.0, "km kilometer kilometers kilometre kilometres")
_units(DISTANCE, 0.3048, 1.0, "ft foot feet")
_units(DISTANCE, 0.0254, 1.0, "inch inches")
_units(DISTANCE, 0.9144, 1.0, "yd yds yard yards")
_units(DISTANCE, 1609.344, 1.0, "mile miles")
_units(ANGLE, 1.0, 1.0, "deg degs degree degrees")
_units(ANGLE, 180.0 / math.pi, 1.0, "rad rads radian radians")
_units(ANGLE, 360.0, 1.0, "turn turns rev revs revolution revolutions rotation rotations")
_units(ANGLE, 360.0, 1.0, "circle circles spin spins")
_units(TIME, 1.0, 1.0, "s sec secs second seconds")
_units(TIME, 1.0, 1000.0, "ms millisecond milliseconds")
_units(TIME, 60.0, 1.0, "min mins minute minutes")
_units(TIME, 3600.0, 1.0, "h hr hrs hour hours")

SPEED_UNITS: dict[str, float] = {
    "m/s": 1.0, "mps": 1.0, "meters per second": 1.0, "metres per second": 1.0,
    "meter per second": 1.0, "metre per second": 1.0, "cm/s": 0.01,
    "km/h": 1 / 3.6, "kph": 1 / 3.6, "kmh": 1 / 3.6, "km per hour": 1 / 3.6,
    "kilometers per hour": 1 / 3.6, "kilometres per hour": 1 / 3.6,
    "mph": 0.44704, "miles per hour": 0.44704,
}  # fmt: skip

DIRECTIONS: dict[str, str] = {}
for _canon, _words in {
    "forward": "forward|forwards|ahead|straight|straight ahead|straight forward|onward|onwards"
    "|to the front|frontward|frontwards",
    "back": "back|backward|backwards|in reverse|reverse|rearward|rearwards|to the rear",
    "left": "left|leftward|leftwards|to the left|to your left|towards the left|toward the left"
    "|to the left side|to your left side|on the left",
    "right": "right|rightward|rightwards|to the right|to your right|towards the right"
    "|toward the right|to the right side|to your right side|on the right",
    "ccw": "counterclockwise|counter clockwise|anticlockwise|anti clockwise|ccw",
    "cw": "clockwise|cw",
    "around": "around|round|the other way|the opposite way|the other direction"
    "|the opposite direction",
    "side": "sideways|sideway|to the side|sidewards|sideward",
    "backforth": "back and forth|forth and back|forward and back|back and forward|to and fro",
}.items():
    for _w in _words.split("|"):
        DIRECTIONS[_w] = _canon

ADVERBS: dict[str, float] = {
    **dict.fromkeys(
        words(
            "quickly|fast|quick|rapidly|briskly|hurriedly|swiftly|speedily|in a hurry|at full speed"
            "|full speed|at top speed",
            "|",
        ),
        0.5,
    ),
    **dict.fromkeys(
        words("slowly|slow|carefully|gently|cautiously|at a slow pace|steadily", "|"), 0.2
    ),
}

FILLERS = frozenset(
    words(
        "the a an by for of your yourself body further farther more another distance way direction"
        " in on to toward towards over exactly just some little bit slightly also too total"
        " approximately about roughly or so then whole"
    )
    + ["in place", "in total", "a little", "a bit", "or so", "from here", "on the spot"]
)


def alternation(phrases: Iterable[str]) -> str:
    """A regex alternation of phrases, longest first, any run of spaces between words."""
    longest_first = sorted(phrases, key=len, reverse=True)
    return "|".join(re.escape(p).replace(r"\ ", r"\s+") for p in longest_first)


def canon(text: str) -> str:
    return " ".join(text.split())


UNIT_ALT = alternation(UNITS)
QTY = re.compile(rf"({NUM})\s*({UNIT_ALT})?(?![\w/])")

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


def to_float(text: str) -> float:
    value = float(text)
    if not math.isfinite(value):
        raise ValueError(f"the number {text[:20]}... is too large")
    return value


def quantity(number: str, unit: str | None) -> Token:
    value = to_float(number)
    if not unit:
        return Token("qty", number, value)
    kind, mul, div = UNITS[canon(unit)]
    if mul != 1.0 or div != 1.0:
        # Rounding hides float noise such as 3 ft = 0.9144000000000001 m.
        value = round(value * mul / div, 9)
    if not math.isfinite(value):
        raise ValueError(f"the quantity {number} {unit} is too large")
    return Token("qty", f"{number} {unit}", value, kind, canon(unit))


def scan(text: str) -> list[Token]:
    """Split a clause remainder into tokens. Raises ValueError for non-finite numbers."""
    tokens: list[Token] = []
    for m in _TOKEN.finditer(text):
        if m.group("speed"):
            speed = to_float(m.group("sn")) * SPEED_UNITS[canon(m.group("su"))]
            tokens.append(Token("speed", m.group(0), round(speed, 9)))
        elif m.group("qty"):
            tokens.append(quantity(m.group("qty"), m.group("unit")))
        elif m.group("dir"):
            tokens.append(Token("dir", DIRECTIONS[canon(m.group("dir"))]))
        elif m.group("adv"):
            tokens.append(Token("adv", m.group("adv"), ADVERBS[canon(m.group("adv"))]))
        elif m.group("word"):
            tokens.append(Token("word", m.group("word")))
    return tokens


# ---- splitting a request into clauses --------------------------------------------------------

_SMALL = words(
    "zero one two three four five six seven eight nine ten eleven twelve thirteen fourteen"
    " fifteen sixteen seventeen eighteen nineteen"
)
_TENS = words("twenty thirty forty fifty sixty seventy eighty ninety")
_VALUES = {w: i for i, w in enumerate(_SMALL)} | {w: 20 + 10 * i for i, w in enumerate(_TENS)}
_SCALES = {"hundred": 100, "thousand": 1000, "million": 1_000_000}
_NUMWORD = alternation([*_VALUES, *_SCALES])
_DIGITWORD = alternation(_SMALL[:10])

_CONTROL = re.compile(r"[\x00-\x08\x0b-\x1f\x7f]")
_THOUSANDS = re.compile(r"(?<=[0-9]),(?=[0-9]{3}(?![0-9]))")
_KEEP_COMMA = re.compile(
    rf"((?:[0-9]|\b(?:{_NUMWORD})\b)\s*),(?=\s*(?:-?\.?[0-9]|(?:minus|negative|{_NUMWORD})\b))",
    re.I,
)
_KEEP_XY = re.compile(r"(\bx\s*[=:]?\s*[\w.-]+)\s*(?:,|\band\b)\s*(?=y\b)", re.I)
_KEEP_AND = re.compile(
    rf"\b(hundred|thousand)\s+and\s+(?=(?:{_NUMWORD})\b)"
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
    r"\s+(?:please|now|robot|buddy|doggy|dog|boy|pup|puppy|shadowhound|go2|thanks|thank you"
    r"|for me|immediately|at once|right away|as well|too|first|next)$"
)
_PLEASE = re.compile(r"\bplease\b")

_TURN_WORDS = r"(?:turn|rotation|revolution|circle|spin)(?!s)\b"
_ONE = r"\b(?:a\s+|one\s+|1\s+)?"
_PHRASES = [
    (re.compile(rf"{_ONE}three\s+quarters?\s+(?:of\s+a\s+)?{_TURN_WORDS}"), "270 deg"),
    (re.compile(rf"{_ONE}quarter\s+(?:of\s+a\s+)?{_TURN_WORDS}"), "90 deg"),
    (re.compile(rf"{_ONE}half\s+(?:a\s+|of\s+a\s+)?{_TURN_WORDS}"), "180 deg"),
    (re.compile(rf"{_ONE}(?:full|complete|whole|entire)\s+{_TURN_WORDS}"), "360 deg"),
    (re.compile(r"\ball\s+the\s+way\s+(?:a)?round\b|\bin\s+a\s+(?:full\s+)?circle\b"), "360 deg"),
    (re.compile(r"\ba\s+(hundred|thousand|million)\b"), r"one \1"),
    (re.compile(r"\ba\s+dozen\b"), "12"),
    (re.compile(r"\b(?:a\s+)?(?:couple|pair)(?:\s+of)?\b"), "2"),
    (re.compile(r"\b(?:a\s+)?few\b"), "3"),
]
_RUN = re.compile(
    rf"\b(?:{_NUMWORD})\b(?:(?:\s+|\s+and\s+)(?:{_NUMWORD})\b)*"
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


def format_number(value: float) -> str:
    if value == int(value) and abs(value) < 1e15:
        return str(int(value))
    return repr(value)


def _words_to_numbers(m: re.Match[str]) -> str:
    words = m.group(0).split()
    decimals = ""
    if "point" in words:
        at = words.index("point")
        decimals = "".join(str(_VALUES[w]) for w in words[at + 1 :])
        words = words[:at]
    groups: list[float] = []
    total = current = 0
    last = ""
    for word in words:
        if word == "and":
            continue
        if word in _SCALES:
            if _SCALES[word] == 100:
                current = (current or 1) * 100
            else:
                total, current = total + (current or 1) * _SCALES[word], 0
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


def normalize(clause: str) -> tuple[str, list[str]]:
    """Lower-case, punctuation-free clause with fillers stripped and numbers in digits."""
    notes: list[str] = []
    text = clause.lower().translate(_CHARMAP)
    text = _CONTRACTION.sub(lambda m: _CONTRACTIONS[m.group(0)], text).replace("'", "")
    text = " ".join(_PUNCT.sub(" ", text).split())
    for _ in range(8):
        before = text
        text = _TRAIL.sub("", _LEAD.sub("", _PLEASE.sub("", text).strip())).strip()
        if text == before:
            break
    if " few" in f" {text}":
        notes.append(f"'a few' in '{clause}' taken as 3")
    for pattern, replacement in _PHRASES:
        text = pattern.sub(replacement, text)
    text = _RUN.sub(_words_to_numbers, text)
    for pattern, repl in _AFTER:
        text = pattern.sub(_after if repl is None else repl, text)
    return " ".join(text.split()), notes


# ---- phrase patterns, matched against normalised clauses ---------------------------------

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
NEGATION = re.compile(r"\b(?:do\s+not|does\s+not|never|not|no\s+longer|can\s+not|will\s+not)\b")
WAIT = re.compile(
    r"^(?:wait|pause|hold\s+on|hold\s+(?:your\s+)?position|hold\s+it|hold|hang\s+on|hang\s+tight"
    r"|stay\s+put|stay|sleep|rest|remain|sit\s+tight|stand\s+still|stay\s+still|hold\s+still"
    r"|keep\s+still|freeze|take\s+a\s+(?:break|breather|rest)|delay|idle|stand\s+by|standby"
    r"|chill|do\s+nothing)(?:\s+(?P<rest>.+))?$"
)
WAIT_WORDS = frozenset(words("here there where you are still quietly put moment while"))
POSTURE = re.compile(
    r"^(?:(?P<lie>(?:lie|lay)(?:\s+(?:yourself\s+)?down)?(?:\s+flat)?|get\s+down|down"
    r"|go\s+(?:to\s+)?sleep|take\s+a\s+nap|nap|stand\s+down|crouch"
    r"|lie\s+on\s+(?:the\s+)?(?:floor|ground))"
    r"|(?P<sit>sit(?:\s+(?:back\s+)?down)?|take\s+a\s+seat|have\s+a\s+seat|be\s+seated)"
    r"|(?P<stand>stand(?:\s+(?:back\s+)?up)?|get\s+(?:back\s+)?up|rise(?:\s+up)?|stand\s+tall"
    r"|stand\s+upright|get\s+on\s+(?:your\s+)?feet|on\s+(?:your\s+)?feet|up|wake\s+up))"
    r"(?:\s+(?P<rest>.+))?$"
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

STATUS = re.compile(
    r"\b(?:battery|batteries|status|charge|charged|power\s+level|health|healthy|diagnostics?"
    r"|how\s+are\s+you|how\s+you\s+are|where\s+are\s+you|where\s+you\s+are|your\s+(?:position"
    r"|location|pose|state|condition|coordinates|heading)|are\s+you\s+(?:ok|okay|alright"
    r"|all\s+right|fine)|sitrep|systems?\s+check)\b"
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
