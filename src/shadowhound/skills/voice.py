"""The voice skill: say words aloud through the robot's speaker (go2_ros2_sdk's tts_node on a
Go2; the simulator records them). Speaking does not move the robot and never waits for the
words to be heard; what is said is cleaned, cut and rate-limited by `speech.Voice`."""

from __future__ import annotations

from pydantic import Field, field_validator

from ..errors import SkillError
from ..speech import MAX_TEXT, clean_speech
from .arguments import SkillArgs
from .context import SkillContext
from .registry import Skill


class SayArgs(SkillArgs):
    text: str | None = Field(
        None,
        min_length=1,
        max_length=MAX_TEXT,
        examples=["I am on my way"],
        description="words to say; none: the latest answer (describe, status)",
    )

    @field_validator("text")
    @classmethod
    def _has_words(cls, value: str | None) -> str | None:
        if value is not None and not clean_speech(value, MAX_TEXT):
            raise ValueError("text has no words to say (only spaces or control characters)")
        return value


def _run_say(ctx: SkillContext, a: SayArgs) -> str:
    text = a.text
    if text is None:
        text = ctx.answer()
        if not text:
            raise SkillError(
                "nothing to say: no step of this mission has answered yet (describe what you "
                "see, report status); give the words to say as text"
            )
    saying = ctx.say(text)
    # The answer is in the mission's response already: name it, do not repeat it.
    what = "the answer" if a.text is None else f'"{saying.text}"'
    if not saying.aloud:
        return f"did not say {what} aloud: {saying.why_silent}"
    cut = " (cut to fit safety.max_speech_chars)" if saying.cut else ""
    return f"said {what} aloud{cut}"


def _phrase(a: SayArgs) -> str:
    return f'say "{a.text}"' if a.text else "say it out loud"


SKILLS = (
    Skill(
        "voice.say",
        "Say text aloud on the robot's speaker (no text: the latest answer). Does not move.",
        SayArgs,
        _run_say,
        timeout=5.0,
        low_battery=True,
        phrase=_phrase,
    ),
)
