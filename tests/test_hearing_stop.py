"""A stop said in everyday words (issues 27, 32): while the robot moves a person says "Stop
walking!", "No, stop!", "Abort the mission!"; each is a stop (the e-stop), however it is said.
A sentence in which stopping is part of a mission ("walk to the stop sign") is a mission."""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound.hearing import is_stop
from shadowhound.hearing.commands import leading_stop

# The issue's phrasings, each queued as a mission behind the running walk before.
ISSUE = [
    "Stop walking!",
    "Stop right there!",
    "No, stop!",
    "Whoa, stop!",
    "Stop that",
    "I said stop",
    "Abort the mission!",
]
MORE = [
    "stop",
    "Stop!",
    "STOP STOP",
    "halt.",
    "e-stop",
    "E stop!",
    "Emergency stop!",
    "stop now please",
    "No!",
    "no no no",
    "Whoa!",
    "Don't move!",
    "Do not move an inch.",
    "Stand still.",
    "Stay right there!",
    "Hold it right there.",
    "Cancel that.",
    "That's enough!",
    "Enough!",
    "Freeze!",
    "Could you please stop?",
    "Hey robot, stop walking forward!",
    "Stop following me.",
    "Stop what you're doing!",
    "Stop walking to the stop sign!",
    "Okay, okay, stop the robot.",
    "I told you to stop!",
    "Cut it out!",
    "Pause the patrol.",
]
MISSIONS = [
    "walk to the stop sign",
    "go to the bus stop",
    "walk until I say stop",
    "stop if you see a person",
    "stop if you see a person and walk forward 1 meter",
    "stop at the kitchen",
    "stop when you reach the door",
    "stop in front of the chair",
    "stop near the red ball",
    "stop for 5 seconds",
    "stop after 2 meters",
    "turn left and stop",
    "walk forward then stop",
    "stop and sit down",
    "don't stop",
    "do not stop walking",
    "never stop",
    "why did you stop?",
    "stop walking to the kitchen and sit",
    "please",
    "",
    "hold",
    "stand up",
]


@pytest.mark.parametrize("said", ISSUE + MORE)
def test_everyday_stops_are_stops(said: str) -> None:
    assert is_stop(said)


@pytest.mark.parametrize("said", MISSIONS)
def test_a_sentence_in_which_stopping_is_part_of_a_mission_is_not_a_stop(said: str) -> None:
    assert not is_stop(said)


# Parts people put together when they want the robot to stop.
INTERJECTIONS = ["no", "hey", "whoa", "oh", "okay", "wait", "hold on", "come on", "emergency"]
ADDRESSED = ["robot", "dog", "buddy", "hey robot", "the robot"]
INSISTING = ["i said", "i told you to", "you need to", "could you", "would you please", "just"]
STOP_VERBS = ["stop", "halt", "freeze", "abort", "cancel", "e-stop", "STOP", "Stop"]
OBJECTS = [
    "",
    "that",
    "it",
    "this",
    "everything",
    "the mission",
    "the walk",
    "your patrol",
    "walking",
    "moving forward",
    "turning left",
    "what you're doing",
    "right there",
    "right now",
    "now",
    "immediately",
    "already",
]
POLITE = ["", "please", "now", "right now", "immediately", "at once", "already"]
PHRASES = ["stand still", "don't move", "do not move", "that's enough", "hold it", "stay put"]
PUNCTUATION = ["", "!", ".", ",", "!!!", "?", "...", " -"]


def _said(parts: list[str], marks: list[str]) -> str:
    return " ".join(p + m for p, m in zip(parts, marks, strict=False) if p)


@st.composite
def stop_phrasings(draw: st.DrawFn) -> str:
    before = draw(st.lists(st.sampled_from(INTERJECTIONS + ADDRESSED + INSISTING), max_size=3))
    core = draw(
        st.one_of(
            st.builds(
                lambda v, o: f"{v} {o}".strip(),
                st.sampled_from(STOP_VERBS),
                st.sampled_from(OBJECTS),
            ),
            st.sampled_from(PHRASES),
        )
    )
    repeats = draw(st.integers(1, 3))
    after = draw(st.lists(st.sampled_from(POLITE + ADDRESSED), max_size=2))
    parts = [*before, *([core] * repeats), *after]
    marks = draw(st.lists(st.sampled_from(PUNCTUATION), min_size=len(parts), max_size=len(parts)))
    said = _said(parts, marks)
    return draw(st.sampled_from([said, said.upper(), said.capitalize()]))


@settings(max_examples=500, deadline=None)
@given(said=stop_phrasings())
def test_any_phrasing_of_stop_is_a_stop(said: str) -> None:
    assert is_stop(said), said


ACTIONS = [
    "walk to the stop sign",
    "walk forward 2 meters",
    "turn left 90 degrees",
    "sit down",
    "go to the kitchen",
    "walk to the bus stop",
]
CONDITIONS = [
    "if you see a person",
    "when you reach the door",
    "until I say stop",
    "at the kitchen",
    "in front of the chair",
    "after 2 meters",
    "near the red ball",
    "for 5 seconds",
    "1 meter before the wall",
]


MISSION_KINDS = ("condition", "stop last", "stop first", "noun", "negated")


@st.composite
def missions_with_stop_words(draw: st.DrawFn, kinds: tuple[str, ...] = MISSION_KINDS) -> str:
    kind = draw(st.sampled_from(kinds))
    verb = draw(st.sampled_from(["stop", "halt", "Stop", "freeze"]))
    action = draw(st.sampled_from(ACTIONS))
    if kind == "condition":  # stopping is what the mission does somewhere, some time
        said = f"{verb} {draw(st.sampled_from(CONDITIONS))}"
    elif kind == "stop last":  # stopping is one step of several
        said = f"{action} and {verb}"
    elif kind == "stop first":
        said = f"{verb} and {action}"
    elif kind == "noun":  # "stop" names a thing
        said = draw(
            st.sampled_from(["walk to the stop sign", "go to the bus stop", "find the stop sign"])
        )
    else:  # the person wants it not to stop
        said = draw(st.sampled_from([f"don't {verb}", f"do not {verb} walking", f"never {verb}"]))
    before = draw(st.lists(st.sampled_from(["please", "hey robot", "okay", "now"]), max_size=2))
    after = draw(st.sampled_from(["", "!", ".", " please", " now"]))
    return " ".join([*before, said]) + after


@settings(max_examples=500, deadline=None)
@given(said=missions_with_stop_words())
def test_a_mission_that_mentions_stopping_is_never_a_stop(said: str) -> None:
    assert not is_stop(said), said


@given(said=st.text(max_size=300))
def test_any_text_is_answered_at_once_and_long_text_is_a_mission(said: str) -> None:
    result = is_stop(said)
    assert isinstance(result, bool)
    assert not is_stop("stop " * 30)  # more words than a stop is said in


BOUNDARIES = [", ", ". ", "! ", " and ", " then ", ", then ", "... and then "]


@settings(max_examples=300, deadline=None)
@given(
    said=stop_phrasings(),
    boundary=st.sampled_from(BOUNDARIES),
    action=st.sampled_from(ACTIONS),
)
def test_a_stop_said_first_is_found_with_what_follows(
    said: str, boundary: str, action: str
) -> None:
    """ "Stop! Turn around.": while the robot moves this is a stop (web/speech.py), and what
    follows is said back as not run."""
    rest = leading_stop(said.rstrip(" .!?,-") + boundary + action)
    assert rest is not None and rest.lower().endswith(action.lower()), (said, rest)


@settings(max_examples=300, deadline=None)
@given(said=missions_with_stop_words(tuple(k for k in MISSION_KINDS if k != "stop first")))
def test_a_mission_that_mentions_stopping_does_not_start_with_a_stop(said: str) -> None:
    """("Stop and sit down" does: said while the robot moves, it stops first.)"""
    assert leading_stop(said) is None, said
