"""Phrases about speaking aloud: "say hello", "say good morning", "announce dinner is ready",
"say what you see", "tell me where you are out loud", "... and say it out loud".

Matched on the clause as the person wrote it, so the words to say keep their case. A clause
asks to speak when it starts with a verb of speaking (say, speak, announce, shout, ...) or ends
with "out loud" / "aloud" (then the clause before it is the question: "describe the room
aloud"). What follows the verb is one of three kinds:
- nothing, or a word standing for an earlier answer ("it", "that", "the answer"): say the
  answer a step before it gave;
- a question ("what you see", "where you are", "how far you walked"): plan the question as
  any clause, then say its answer (if the question is not understood, its words are said);
- anything else: the words to say, greetings said as a greeting ("Good morning!").
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from shadowhound.planning._phrases import repetition

_FILLER = re.compile(
    r"^(?:(?:please|kindly|now|then|and|also|ok|okay|(?:can|could|would|will)\s+you"
    r"(?:\s+please)?|i\s+(?:want|would\s+like|need)\s+you\s+to|go\s+ahead\s+and|just)\s+)+"
)
_SPEAK = re.compile(
    r"^(?:say|speak|announce|shout|yell|whisper|utter|read\s+out)"
    r"(?:\s+(?:out|aloud|out\s+loud|loudly))?(?:\s*[:,]\s*|\s+|$)"
)
# "read it out loud", "tell us that aloud": the verb before a word for an earlier answer.
_PASS_ON = re.compile(
    r"^(?:(?:read|repeat|tell|give|report|share)(?:\s+(?:me|us|them|everyone))?\s*)?"
)
_ALOUD = re.compile(
    r"[\s,]+(?:out\s+loud|aloud|loudly|loud\s+and\s+clear|with\s+your\s+voice"
    r"|(?:through|on|over)\s+(?:the|your)\s+speakers?)$"
)
_TRAIL = re.compile(r"[\s,]+(?:please|for\s+me|for\s+us|now|again)$")
_ANSWER = re.compile(
    r"^(?:it|that|this|so|them|those|these|(?:the|your|that|this)\s+(?:answer|result|reply"
    r"|report|description|findings?))?$"
)
_QUESTION = re.compile(r"^(?:what|where|how|which|who|whether|if|why|when)\b")
GREETING = re.compile(
    r"^(?:hello|hi|hey|hiya|howdy|greetings|welcome|good\s*bye|bye|farewell"
    r"|good\s+(?:morning|afternoon|evening|night|day))\b"
)
_TO_SOMEONE = re.compile(r"^(?:to|at|with)\b")
_QUOTES = "\"'\u201c\u201d\u2018\u2019`"


@dataclass(frozen=True)
class SpeechRequest:
    """A clause that asks to speak. `question`: a clause whose answer is to be said (None when
    there is none); `text`: the words to say when there is no question to answer (or it is not
    understood); neither: say the answer of a step before it."""

    question: str | None = None
    text: str | None = None
    greeting: bool = False
    count: int = 1  # "say hello twice"


def speech_request(label: str) -> SpeechRequest | None:
    """What a clause asks to say, or None when it does not ask to speak aloud."""
    raw = " ".join(label.split()).rstrip(" .!?;")
    low = raw.lower()
    start = _FILLER.match(low)
    at = start.end() if start else 0
    aloud = _ALOUD.search(low, at)
    end = aloud.start() if aloud else len(low)
    trail = _TRAIL.search(low[:end], at)
    end = trail.start() if trail else end
    verb = _SPEAK.match(low[at:end])
    if verb is None:
        if aloud is None:
            return None
        question = raw[at:end].strip()
        rest = question.lower()
        if _ANSWER.match(rest[_PASS_ON.match(rest).end() :]):  # type: ignore[union-attr]
            return SpeechRequest()
        return SpeechRequest(question=question)
    what = raw[at + verb.end() : end].strip().strip(_QUOTES).strip()
    if _TO_SOMEONE.match(what.lower()):  # "speak to me": not words to say
        return None
    if _ANSWER.match(what.lower()):
        return SpeechRequest()
    if _QUESTION.match(what.lower()):
        return SpeechRequest(question=what, text=_sentence(what, False))
    count = 1
    try:
        rest, count, how = repetition(what.lower())
    except ValueError:  # "2.5 times": not a count, so words to say
        rest, how = what.lower(), ""
    if how:
        what, count = what[: len(rest)], count + 1 if how == "more" else count
    greeting = GREETING.match(what.lower())
    if greeting and _TO_SOMEONE.match(what.lower()[greeting.end() :].strip()):
        what = what[: greeting.end()]  # "say hello to the visitors": the greeting, waved at them
    return SpeechRequest(text=_sentence(what, bool(greeting)), greeting=bool(greeting), count=count)


def _sentence(words: str, greeting: bool) -> str:
    """The words as said: a capital first letter; a greeting ends in '!'."""
    words = words[:1].upper() + words[1:]
    if greeting and words[-1:] not in (".", "!", "?"):
        words += "!"
    return words
