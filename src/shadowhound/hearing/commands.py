"""Spoken words that are not a mission: a stop, said however people say it.

A transcript is a stop when every word of it belongs to a way of saying stop (English):

- a stop word: stop, halt, freeze, e-stop, cease, abort, cancel, quit, pause, enough, whoa,
  and "no" said on its own, each optionally followed by what to stop: it, that, this,
  everything, the mission (walk, task, patrol, robot ...), a motion ("walking", "moving
  forward", "turning left", "following me", "walking to the kitchen"), "what you're doing",
  or where ("right there", "here", "where you are", "in your tracks");
- or a phrase of stopping: stand/stay/hold/keep still, stay put, stay (right) there, hold it,
  hold up, don't move (any further, an inch, a muscle), don't go any further, not another
  step, that's enough, that will do, cut it out, knock it off;
- and around them only fillers: interjections (no, hey, whoa, oh, okay, wait, hold on ...),
  politeness (please, kindly, could you, would you), insistence (I said, I told you to, you
  need to, now, right now, immediately, again), who is spoken to (robot, dog, buddy), and
  repeats, in any case, with any punctuation.

So "Stop walking!", "No, stop!", "Whoa, stop!", "I said stop", "Abort the mission!" are stops;
a sentence in which stopping is part of a mission is not: "walk to the stop sign", "walk until
I say stop", "stop if you see a person", "stop at the kitchen", "stop and sit down", "don't
stop". Words are matched phrase by phrase over at most `MAX_WORDS` words (a longer transcript
is a mission), each position once: the cost is linear and small.

`leading_stop` finds a stop said first, before more ("Stop! Turn around.", "No, stop, and sit
down"): the longest start of the transcript, up to a sentence's end, a comma, "and" or "then",
that is a stop, and what follows it. While the robot moves that is a stop too (web/speech.py).
"""

from __future__ import annotations

import re
from itertools import product

MAX_WORDS = 24  # a stop is said in a few words; a longer transcript is a mission
_LONGEST = 6  # words in the longest phrase below


def _expand(*patterns: str) -> set[str]:
    """Phrases from patterns of alternatives: "(stand|stay) still|stay put" -> {"stand still",
    "stay still", "stay put"}; an empty alternative makes a part optional: "(the|) walk".
    Groups do not nest."""
    out: set[str] = set()
    for pattern in patterns:
        for alternative in re.split(r"\|(?![^()]*\))", pattern):  # "|" outside groups
            parts = re.split(r"\(([^()]*)\)", alternative)
            choices = [p.split("|") if i % 2 else [p] for i, p in enumerate(parts)]
            out.update(" ".join("".join(c).split()) for c in product(*choices))
    return out


_FILLERS = _expand(
    "(no|nope|hey|oh|ah|uh|um|hmm|ok|okay|right|yes|yeah|wait|hold on|hang on|come on|oops)",
    "(whoops|ouch|ow|man|dude|guys|everyone|everybody|listen|careful|be careful|danger)",
    "(watch out|look out|seriously|emergency|god|oh my god|omg|jesus|damn|damn it|dammit)",
    "(for gods sake|for gods sakes|please|kindly|now|right now|at once|immediately|quickly)",
    "(quick|just|again|already|i said|i said to|i say|i told you|i told you to|i am telling you)",
    "i am telling you to|i want you to|i need you to|(can|could|would|will) you|you",
    "would you kindly|you (need|have|must|should|gotta|got) to|you must|you should|let us",
    "(hey|) (you|robot|dog|doggy|doggie|buddy|boy|girl|shadowhound|shadow hound|go2)",
    "(the|my) (robot|dog)",
)
_STOP_WORDS = _expand(
    "(stop|halt|freeze|estop|cease|abort|cancel|quit|pause|enough|whoa|woah|whoah|no)",
    "(stop|halt|freeze) (it|that|this)",
)
_OBJECTS = _expand(
    "(it|that|this|everything|all|all of it|all of that|already|dead|please|now|right now)",
    "right away|at once|immediately|for now|for a (second|moment|sec)|of that|of this",
    "(right|) (there|here)|where you are|in your tracks|what(ever|) you are doing",
    "(the|this|that|your|my|) (mission|missions|task|patrol|plan|command|commands|order)",
    "(the|this|that|your|my|) (motion|movement|robot|dog|program|tour|route|thing)",
    "(the|this|that|your|my) (turn|move|run|walk|drive|trip)",  # without one, an imperative
    "(the|this|that|your|my|) whole thing|all (motion|movement|moving)",
)
_MOTIONS = _expand(
    "(moving|walking|running|going|turning|rotating|spinning|driving|following|coming|heading)",
    "backing up|backing|pacing|trotting|marching|doing (that|this|it|everything)",
)
_TAILS = _expand(
    "(forward|forwards|backward|backwards|back|ahead|left|right|around|away|up|now|there)",
    "(me|us|him|her|them|it|toward me|towards me|to me)",
)
_PHRASES = _expand(
    "(stand|stay|hold|keep|be|remain|sit) still|stay put|(stay|hold) (right|) there",
    "stay where you are|hold (it|up|your position|position)|hold it right there",
    "do not (move|budge|step|walk|go|run|turn|take another step|go anywhere|move a muscle)",
    "do not (go|move|walk) any (further|farther|more)|do not move an inch|not another step",
    "that is enough|that will do|cut it out|knock it off|no more|never move",
)
_TOWARD = _expand("(to|toward|towards|over to|back to|into) (the|a|that|this|)")
_NOT_A_PLACE = {"if", "until", "unless", "when", "while", "and", "then", "but", "after", "before"}

FILLER, STOP, OBJECT, MOTION, TAIL, TOWARD = (
    "filler",
    "stop",
    "object",
    "motion",
    "tail",
    "toward",
)
_KINDS: dict[str, set[str]] = {}
for _kind, _words in (
    (FILLER, _FILLERS),
    (STOP, _STOP_WORDS | _PHRASES),
    (OBJECT, _OBJECTS),
    (TAIL, _TAILS),
    (MOTION, _MOTIONS),
    (TOWARD, _TOWARD),
):
    for _phrase in _words:
        _KINDS.setdefault(_phrase, set()).add(_kind)

_CONTRACTIONS = {
    "don't": "do not",
    "dont": "do not",
    "that's": "that is",
    "thats": "that is",
    "let's": "let us",
    "lets": "let us",
    "you're": "you are",
    "youre": "you are",
    "i'm": "i am",
    "god's": "gods",
    "what're": "what are",
}
_WORD = re.compile(r"[a-z0-9']+")

# What may follow what: after a stop word, what to stop; after a motion, its direction or
# where it was going; fillers anywhere.
_AFTER = {
    None: {FILLER, STOP},
    FILLER: {FILLER, STOP},
    STOP: {FILLER, STOP, OBJECT, MOTION},
    OBJECT: {FILLER, STOP, OBJECT, MOTION},
    MOTION: {FILLER, STOP, OBJECT, TAIL, TOWARD},
    TAIL: {FILLER, STOP, OBJECT, TAIL},
    TOWARD: {"place"},
    "place": {FILLER, STOP, OBJECT, "place"},
}


_BOUNDARY = re.compile(
    r"\s*[.!?;,][\s.!?;,]*(?:(?:and\s+then|and|then)\s+)?|\s+(?:and\s+then|and|then)\s+",
    re.IGNORECASE,
)


def leading_stop(transcript: str) -> str | None:
    """What follows a stop said first ("Stop! Turn around." -> "Turn around."), or None when
    the transcript does not start with a stop followed by more words (or is only a stop)."""
    if is_stop(transcript):
        return None
    rest = None
    for boundary in _BOUNDARY.finditer(transcript):
        head, tail = transcript[: boundary.start()], transcript[boundary.end() :]
        if len(words_of(head)) > MAX_WORDS:
            break
        if words_of(tail) and is_stop(head):
            rest = tail.strip()
    return rest


def words_of(transcript: str) -> list[str]:
    """The transcript's words, lower case, contractions spelled out, "e-stop" one word."""
    text = transcript.lower().replace("\u2019", "'")
    text = re.sub(r"\be[\s-]+stop\b", "estop", text)
    words = []
    for word in _WORD.findall(text):
        words.extend(_CONTRACTIONS.get(word, word.strip("'")).split())
    return [w for w in words if w]


def is_stop(transcript: str) -> bool:
    """Whether the transcript only says stop, in any of the ways above."""
    words = words_of(transcript)
    if not words or len(words) > MAX_WORDS:
        return False
    # Walk the words left to right: at each position, the kinds of phrase that may end there
    # (and whether a stop has been said); each position is visited once per state.
    states: dict[int, set[tuple[str | None, bool]]] = {0: {(None, False)}}
    for i in range(len(words)):
        for last, stopped in states.pop(i, set()):
            for n in range(1, min(_LONGEST, len(words) - i) + 1):
                phrase = " ".join(words[i : i + n])
                for kind in _kinds(phrase, last, n):
                    states.setdefault(i + n, set()).add((kind, stopped or kind == STOP))
    return any(stopped for _last, stopped in states.get(len(words), set()))


def _kinds(phrase: str, last: str | None, n: int) -> set[str]:
    allowed = _AFTER[last]
    kinds = _KINDS.get(phrase, set()) & allowed
    if "place" in allowed and n <= 2 and not set(phrase.split()) & _NOT_A_PLACE:
        kinds = kinds | {"place"}  # where a motion was going: "walking to the kitchen"
    return kinds
