"""How `conditions` reads a request: words as tokens, and the kinds of conditions among them.

`tokens` cuts a request into canonical words (lower case, contractions spelt out, misspelt
condition words read as the words they stand for, words to say or remember left out), each
with where it was written; `scan` finds where each condition starts and its kind, with the
exceptions `conditions` documents (embedded questions, hedges, sequences, counts).
"""

from __future__ import annotations

import re
from collections.abc import Iterator
from dataclasses import dataclass
from functools import cache

from ..typos import distance, limit
from ._numbers import NUMWORD
from ._spelling import known_words
from ._text import words

# ---- reading the words -----------------------------------------------------------------------

_QUOTES = str.maketrans({"\u2019": "'", "\u2018": "'", "\u201c": '"', "\u201d": '"'})
# Words to say or to remember are content, not conditions: blanked, keeping every position.
_CONTENT = re.compile(
    r"\"[^\"]*\"?|(?<![\w'])'[^']*'(?![\w])"
    r"|\b(?:remember|note|keep\s+in\s+mind|learn|memori[sz]e|(?:say|announce|shout|whisper"
    r"|tell\s+(?:him|her|them|everyone|everybody|people))\s+that)\b"
    r"(?:(?!\s+(?:and\s+)?then\b|,\s*(?:and\s+)?then\b)[^.;!?\n])*",
    re.I,
)
_TOKEN = re.compile(r"[0-9]+(?:\.[0-9]+)?%?|'?[^\W\d_]+(?:'[^\W\d_]+)*|[,;:.!?\n]")
_BOUNDARY = ","
_CONTRACTIONS = {
    "'til": "until", "'till": "until", "til": "until", "till": "until", "cannot": "can not",
    "can't": "can not", "won't": "will not", "don't": "do not", "doesn't": "does not",
    "didn't": "did not", "dont": "do not", "let's": "let us", "it's": "it is",
    "that's": "that is", "there's": "there is", "what's": "what is", "who's": "who is",
}  # fmt: skip
_SUFFIXES = {"n't": "not", "'re": "are", "'ve": "have", "'ll": "will", "'m": "am", "'d": "would"}


@dataclass(frozen=True)
class Token:
    word: str  # the canonical word ("untill" -> "until"), or "," for a boundary
    start: int
    end: int


def _blank_content(text: str) -> str:
    return _CONTENT.sub(lambda m: " " * len(m.group(0)), text)


def tokens(text: str) -> list[Token]:
    """The words of `text` in order, "," for a clause boundary."""
    text = _blank_content(text.translate(_QUOTES))
    found = []
    for m in _TOKEN.finditer(text):
        raw = m.group(0).lower()
        if not raw[0].isalnum() and raw[0] != "'":
            found.append(Token(_BOUNDARY, m.start(), m.end()))
            continue
        for word in _canonical(raw):
            found.append(Token(word, m.start(), m.end()))
    return found


def _canonical(raw: str) -> list[str]:
    if raw in _CONTRACTIONS:
        return _CONTRACTIONS[raw].split()
    for suffix, word in _SUFFIXES.items():
        if raw.endswith(suffix) and len(raw) > len(suffix):
            return [*_canonical(raw[: -len(suffix)]), word]
    raw = raw.strip("'").removesuffix("'s")  # a possessive, or "somebody's": the noun will do
    return [_read_typo(raw)]


# Condition words a typo is read as; short ones ("if", "when", "once") are never guessed.
_TYPO_TARGETS = ("until", "unless", "while", "otherwise", "whenever", "follow", "following")
# Real words near them, which are never a typo of one.
_NEAR_WORDS = frozenset(
    words(
        "whale whole white whine whiled whiles wile wiles untie untied unlit fellow fellows fallow "
        "follows followed follower followers hollow whatever wherever whoever whichever otherwhere "
        "unleash until unless while whilst otherwise whenever follow following"
    )
)


@cache
def _read_typo(word: str) -> str:
    """`word`, or the condition word it is a misspelling of."""
    if len(word) < 4 or not word.isalpha() or word in _NEAR_WORDS or word in known_words():
        return word
    near = {
        target: distance(word, target, limit(word))
        for target in _TYPO_TARGETS
        if target[0] == word[0]
    }
    best = [t for t, d in near.items() if d <= limit(word) and d == min(near.values())]
    return best[0] if len(best) == 1 else word  # "followng": following, not follow


# ---- kinds of conditions ---------------------------------------------------------------------

_SUBJECTS = frozenset(
    words(
        "i you we he she they it there someone somebody anyone anybody everyone everybody nobody "
        "something anything nothing people the a an my your our his her their its this that these "
        "those"
    )
)
_PEOPLE = frozenset(
    words("i you we he she they someone somebody anyone anybody everyone everybody nobody people")
)
_DETERMINERS = frozenset(words("the a an my your our his her their its this that these those"))
_OBJECTS = frozenset(words("me us them him her you everyone everybody it"))
# Verbs that make "if" / "whether" / "when" ask a question rather than set a condition.
_ASKING = frozenset(
    words(
        "tell ask know check see find figure work determine wonder say report show confirm verify "
        "decide look learn guess remember recall"
    )
)
_RELATIVES = frozenset(words("what whatever which where how who everything all"))
_AUXILIARIES = frozenset(
    words(
        "did do does was were is are am will would can could have has had should shall must might "
        "may"
    )
)
_HEDGES = (
    ("any",), ("anything",), ("you", "can"), ("you", "could"), ("you", "like"),
    ("you", "want"), ("you", "wish"), ("you", "please"), ("you", "would"), ("you", "are", "able"),
    ("you", "do", "not", "mind"), ("ready",), ("you", "are", "ready"), ("convenient",),
    ("you", "get", "a", "chance"), ("you", "have", "time"), ("it", "is", "possible"),
)  # fmt: skip
# What follows "when you ..." / "once you ..." when it only says what comes next: the robot's
# own doing, which a sequence of steps expresses.
_OWN = frozenset(
    words(
        "done finished finish through ready complete completed back there home here arrive arrived "
        "arrives return returned stand stood sit sat lie lay lain walk walked move moved go went "
        "gone turn turned rotate rotated spin spun look looked come came stop stopped do did start "
        "started wake woke say said run ran trot trotted step stepped"
    )
)
_ARRIVE = frozenset(words("get got reach reached"))  # own only with there/back/home/it
_PLACES_REACHED = frozenset(words("there back home here it up down"))
_AUX_AFTER_YOU = frozenset(words("have are were had will can could just finally first then all"))
_PAST = frozenset(
    words(
        "saw was were did had went came got found heard met took sat stood ran began spoke said "
        "told knew thought felt lost made gave caught brought held kept slept"
    )
)
_ED_NOT_PAST = frozenset(words("need speed feed proceed exceed succeed bleed breed seed shed"))
_TOLD = frozenset(words("told say said stated instructed"))  # "unless told otherwise"
_TRIGGERS = frozenset(["when", "whenever", "once", "after", "before"])
_MOMENTS = frozenset(words("moment second instant minute"))
_FOLLOW = frozenset(
    words(
        "follow follows following track tracking tail tailing chase chasing pursue pursuing shadow "
        "shadowing"
    )
)
# What is followed without tracking anybody: instructions, a lead, a route.
_NOT_FOLLOWED = frozenset(
    words(
        "instructions instruction steps step orders order rules rule commands command directions "
        "plan lead suit up through route routine recipe example advice protocol procedure script "
        "sequence pattern list along down of"
    )
)
_CHASED = frozenset(words("the a my your him her them me us")) | _PEOPLE - {"i", "we"}
_WATCH = frozenset(words("watch watching listen listening"))
_WITH = frozenset(words("come walk stay stick keep"))  # "come with me", "keep up with me"
_TIMES = frozenset(
    words(
        "second seconds sec secs minute minutes min mins hour hours moment bit while few couple "
        "little time"
    )
)


def scan(words: list[str]) -> Iterator[tuple[int, str]]:
    """(where the condition's words start, its kind) for each condition in `words`."""
    for i, w in enumerate(words):
        prev = words[i - 1] if i else _BOUNDARY
        rest = _clause(words, i + 1)
        if w in ("until", "unless"):
            yield i, w
        elif w == "if":
            if prev not in ("as", "even", "what") and not _asked(words, i) and not _hedge(rest):
                yield i, "if"
        elif w == "otherwise" and prev not in _TOLD:
            yield i, "otherwise"
        elif w == "else" and prev in ("or", _BOUNDARY, "and"):
            yield (i - 1 if prev == "or" else i), "otherwise"
        elif w in ("while", "whilst"):
            if prev not in ("a", "worth", "your") and rest and not _gerund(rest[0]):
                yield i, "while"
        elif w in ("as", "so") and rest[:2] == ["long", "as"]:
            yield i, "as long as"
        elif w == "in" and rest[:1] == ["case"]:
            if prev != "just" or rest[1:]:
                yield i, "in case"
        elif w in ("provided", "providing", "assuming") and rest[:1] and rest[0] in _SUBJECTS:
            yield i, "provided"
        elif w == "depending" and rest[:1] == ["on"]:
            yield i, "depending on"
        elif w == "wait" and rest[:1] == ["for"] and rest[1:] and not _a_time(rest[1:]):
            yield i, "wait for"
        elif kind := _trigger(words, i, rest):
            yield i, kind
        elif kind := _watch_or_follow(words, i, rest):
            yield (i - 1 if prev in ("keep", "continue") else i), kind  # "keep following"


def _gerund(word: str) -> bool:
    """ "looking" in "while looking around": an action at the same time, not a condition."""
    return word.endswith("ing") and word not in ("nothing", "something", "anything", "everything")


def _clause(words: list[str], start: int) -> list[str]:
    """The words from `start` to the end of their clause."""
    end = start
    while end < len(words) and words[end] != _BOUNDARY:
        end += 1
    return words[start:end]


def _hedge(rest: list[str]) -> bool:
    """The words after "if"/"when" are a courtesy ("if you can", "if possible"), not a condition:
    they end the clause, or ("possible", "any") can start none."""
    if rest[:1] == ["possible"]:
        return True
    for hedge in _HEDGES:
        n = len(hedge)
        if tuple(rest[:n]) == hedge and (len(rest) == n or rest[n] in ("and", "then", "please")):
            return True
    return False


def _asked(words: list[str], i: int) -> bool:
    """Whether the "if"/"when" at `i` opens an embedded question: "tell me if ...", "ask the
    visitor if ...", "can you see if ...", "let me know if ..."."""
    j = i - 1
    if j >= 0 and words[j] == "please":
        j -= 1
    if j >= 0 and words[j] in _OBJECTS and words[j] not in ("you",):
        j -= 1
    elif j >= 1 and words[j - 1] in _DETERMINERS:
        j -= 2  # "ask the visitor if"
    if j >= 0 and words[j] == "out":  # "find out if", "figure out if"
        j -= 1
    if j < 0 or words[j] not in _ASKING:
        return False
    # "what you see if ..." says what is seen (then "if" sets a condition); "I wonder if ...",
    # "can you see if ..." ask.
    return not (j >= 2 and words[j - 1] in _PEOPLE and words[j - 2] in _RELATIVES)


def _trigger(words: list[str], i: int, rest: list[str]) -> str:
    """ "when you see a cat", "once the person leaves", "as soon as I say go": the kind, or ""."""
    w = words[i]
    prev = words[i - 1] if i else _BOUNDARY
    if w == "as" and words[i + 1 : i + 3] == ["soon", "as"]:
        w, rest = "as soon as", rest[2:]
    elif w in ("every", "each", "any", "anytime") and (w == "anytime" or rest[:1] == ["time"]):
        if w != "anytime":
            rest = rest[1:]
        w = "every time"
        if not rest or rest[0] not in _SUBJECTS:
            return ""
    elif w == "the" and rest[:1] and rest[0] in _MOMENTS:
        rest = rest[1:]
        if rest[:1] == ["that"]:
            rest = rest[1:]
        if not rest or rest[0] not in _PEOPLE:
            return ""
        w = "the " + words[i + 1]
    elif w not in _TRIGGERS:
        return ""
    if not rest or rest[0] == "to" or _hedge(rest):
        return ""  # "say when", "decide when to turn", "when possible"
    if w == "once" and (prev == "at" or rest[0] not in _SUBJECTS or _a_time(rest[1:])):
        return ""  # "wave once", "at once", "once a day"
    if w in ("after", "before") and not (rest[0] in _PEOPLE or _happens(rest)):
        return ""  # "after that", "after 5 seconds", "before moving", "after the walk"
    if w == "when" and prev in (_BOUNDARY, "and", "but") and rest[0] in _AUXILIARIES:
        return ""  # a question: "when did you see the ball?"
    if w in ("when", "once", "after", "before", "as soon as") and _sequence(rest):
        return ""
    if _past(rest):
        return ""  # a time gone by: "tell me when you last saw it"
    return w


def _happens(rest: list[str]) -> bool:
    """The words are a thing and what it does ("the red ball leaves", "the door is open"),
    not a thing alone ("the walk")."""
    if not rest or rest[0] not in _DETERMINERS:
        return False
    return any(w in _AUXILIARIES or (w.endswith("s") and len(w) > 3) for w in rest[2:8])


def _sequence(rest: list[str]) -> bool:
    """The clause after "when"/"once" only says what comes next: "you are done", "you get
    there", "that is finished", "done"."""
    if rest[0] in ("done", "finished", "complete", "ready", "through"):
        return True
    if rest[0] in ("there", "back"):  # "once there", not "when there is a person"
        return rest[1:2] not in (["is"], ["are"], ["was"], ["were"])
    if rest[0] in _SUBJECTS - _PEOPLE:  # "that is done", "the walk is over"
        tail = [w for w in rest[1:6] if w not in ("is", "has", "been", "was")]
        done = ("done", "finished", "over", "complete", "completed")
        return any(w in done for w in tail) and len(tail) <= 3
    if rest[0] != "you":
        return False
    k = 1
    while k < len(rest) and rest[k] in _AUX_AFTER_YOU:
        k += 1
    if k >= len(rest):
        return False
    verb = rest[k]
    if verb in _ARRIVE:
        return k + 1 >= len(rest) or rest[k + 1] in _PLACES_REACHED
    return verb in _OWN or verb.removesuffix("s") in _OWN or verb.removesuffix("ing") in _OWN


def _past(rest: list[str]) -> bool:
    """The clause tells of the past ("you saw the ball", "the person left"): no trigger."""
    for k, word in enumerate(rest[:6]):
        before = rest[k - 1] if k else ""
        if before in ("is", "are", "am", "be", "been", "being", "get", "gets", "have", "has"):
            continue
        if word in _PAST or (len(word) > 4 and word.endswith("ed") and word not in _ED_NOT_PAST):
            return True
    return False


def _a_time(rest: list[str]) -> bool:
    """The words name a time or a count: "5 seconds", "a moment", "a day", "two minutes"."""
    head = rest[:3]
    return bool(head) and (
        _number(head[0])
        or any(w in _TIMES or w in ("day", "week", "hour", "year") for w in head[:2])
        or head[0] in ("more", "again", "every", "per")
    )


def _number(word: str) -> bool:
    return word[:1].isdigit() or _NUMBER_WORD.fullmatch(word) is not None


_NUMBER_WORD = re.compile(rf"(?:{NUMWORD})")


def _watch_or_follow(words: list[str], i: int, rest: list[str]) -> str:
    """ "follow the person", "come with me", "watch for people", "keep an eye on the door"."""
    w = words[i]
    prev = words[i - 1] if i else _BOUNDARY
    if w in _FOLLOW and prev not in _DETERMINERS and prev not in ("as", "be"):
        thing = next((x for x in rest if x not in _DETERMINERS), "")
        return "" if thing in _NOT_FOLLOWED else "follow"
    if w in _WITH and rest[:2] in (["with", "me"], ["with", "us"]):
        return "follow"
    if w in _WITH and rest[:3] in (["up", "with", "me"], ["up", "with", "us"]):
        return "follow"
    if w == "stay" and rest[:2] in (["close", "to"], ["near", "me"], ["behind", "me"]):
        return "follow"
    if w == "go" and rest[:1] == ["after"] and rest[1:2] and rest[1] in _CHASED:
        return "follow"
    if w in _WATCH and (rest[:1] == ["for"] or rest[:2] == ["out", "for"]):
        return "watch"
    if w == "look" and rest[:2] == ["out", "for"]:
        return "watch"
    if w == "keep" and (rest[:2] == ["an", "eye"] or rest[:1] == ["watch"]):
        return "watch"
    if w in ("lookout", "guard") and prev in ("the", "on"):
        return "watch"
    return ""


def clause_end(tokens: list[Token], start: int) -> int:
    """Where the words of the condition starting at `start` end: at the end of its clause,
    at "and" / "then" / "but", or where another branch starts."""
    end = start + 1
    while end < len(tokens):
        word = tokens[end].word
        branch = word == "otherwise" and tokens[end - 1].word not in _TOLD
        if (
            branch
            or word in (_BOUNDARY, "and", "then", "but")
            or (word == "or" and end + 1 < len(tokens) and tokens[end + 1].word == "else")
        ):
            break
        end += 1
    return end
