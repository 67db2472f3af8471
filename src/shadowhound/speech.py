"""What the robot may say aloud: words cleaned and cut to a length, at a bounded rate.

Every saying passes `Voice.speak` before it reaches a robot's speaker (`Robot.say`), whoever
wrote the words (a person, a planner, a model's answer): control characters go, whitespace
runs become one space, the text is cut at a word to `safety.max_speech_chars`, and at most
`safety.max_speech_per_minute` sayings are spoken in any minute of the robot's clock. A saying
over the rate, or on a robot without a voice, is not spoken; `Saying.why_silent` says why.
Speaking never waits for the words to be heard: robots queue them and return at once.
"""

from __future__ import annotations

import re
import threading
import unicodedata
from collections import deque
from dataclasses import dataclass
from typing import TYPE_CHECKING, Protocol

from .errors import RobotError

if TYPE_CHECKING:
    from .config import ShadowHoundConfig

MAX_TEXT = 500  # characters a skill call may ask to say; the profile's cut is at most this
WINDOW = 60.0  # seconds of the rate limit
_SPACE = re.compile(r"\s+")


def clean_speech(text: str, limit: int) -> str:
    """`text` as it may be spoken: no control or format characters, whitespace as single
    spaces, at most `limit` characters (cut at a word, ending in '...')."""
    kept = "".join(
        " " if unicodedata.category(ch).startswith(("C", "Z")) else ch for ch in str(text)
    )
    words = _SPACE.sub(" ", kept).strip()
    if len(words) <= limit:
        return words
    cut = words[: max(1, limit - 3)]
    if " " in cut[limit // 2 :]:
        cut = cut[: cut.rindex(" ")]
    return cut.rstrip(" ,;:-") + "..."


class Speaker(Protocol):
    """What the voice needs of a robot (`Robot` has both): its clock and its speaker."""

    def now(self) -> float: ...

    def say(self, text: str) -> None: ...


@dataclass(frozen=True)
class Saying:
    """What became of one request to speak: the words (cleaned and cut), and why they were
    not spoken aloud ("" when they were)."""

    text: str
    why_silent: str = ""
    cut: bool = False  # the text was longer than the limit

    @property
    def aloud(self) -> bool:
        return not self.why_silent


class Voice:
    """The robot's one mouth, shared by every mission of an agent: the cleaning, the cut and
    the rate limit (on the robot's clock). Thread-safe."""

    def __init__(self, settings: ShadowHoundConfig) -> None:
        self.settings = settings  # its `safety` is read at each saying (it may be replaced)
        self._spoken: deque[float] = deque()  # robot times of recent sayings
        self._lock = threading.Lock()

    def speak(self, robot: Speaker, text: str) -> Saying:
        """Say `text` on `robot` unless the rate is spent or the robot has no voice; returns at
        once. Raises ValueError when nothing is left to say once the text is cleaned."""
        safety = self.settings.safety
        limit = safety.max_speech_chars
        whole = clean_speech(text, len(str(text)))
        if not whole:
            raise ValueError("there are no words to say (empty after removing control characters)")
        words, cut = clean_speech(whole, limit), len(whole) > limit
        per_minute = safety.max_speech_per_minute
        with self._lock:
            now = robot.now()
            while self._spoken and now - self._spoken[0] >= WINDOW:
                self._spoken.popleft()
            if len(self._spoken) >= per_minute:
                why = (
                    "speaking aloud is off (safety.max_speech_per_minute is 0)"
                    if per_minute == 0
                    else f"over the rate: it may say {per_minute} a minute "
                    "(safety.max_speech_per_minute)"
                )
                return Saying(words, why, cut)
            try:
                robot.say(words)
            except RobotError as exc:
                return Saying(words, str(exc), cut)
            self._spoken.append(now)
        return Saying(words, "", cut)
