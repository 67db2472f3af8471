"""Forgiving English in the offline planner: misspellings of its own words read by edit distance
and said back to the user; postures with extra words; and still no guessing: conditions,
negations, unknown objects and ambiguous words are refused, naming the words."""

from __future__ import annotations

import pytest
from hypothesis import assume, example, given, settings
from hypothesis import strategies as st

from shadowhound.plan import PlanningError
from shadowhound.planning import _spelling as spelling
from shadowhound.planning.rules import RulePlanner

PLANNER = RulePlanner()


def steps(text: str) -> list[tuple[str, dict]]:
    return [(s.skill, s.args) for s in PLANNER.plan(text).steps]


def refusal(text: str) -> str:
    with pytest.raises(PlanningError) as info:
        PLANNER.plan(text)
    return info.value.message


# -- misspellings, by kind of word -------------------------------------------------------------


@pytest.mark.parametrize(
    "typo,clean,read",
    [
        ("rotaet right 30 degrees", "rotate right 30 degrees", ("rotaet", "rotate")),  # verb, swap
        ("stafe left half a meter", "strafe left half a meter", ("stafe", "strafe")),  # verb, drop
        ("move backwrd 40 cm", "move backward 40 cm", ("backwrd", "backward")),  # direction
        (
            "turn counterclokwise 15 degrees",
            "turn counterclockwise 15 degrees",
            ("counterclokwise", "counterclockwise"),
        ),  # long word
        (
            "walk forward three metres quikcly",
            "walk forward three metres quickly",
            ("quikcly", "quickly"),
        ),  # adverb
        ("go ahead siex meters", "go ahead six meters", ("siex", "six")),  # number
        (
            "walk forward twnety centimeters",
            "walk forward twenty centimeters",
            ("twnety", "twenty"),
        ),  # number
        ("wait for 4 secodns", "wait for 4 seconds", ("secodns", "seconds")),  # unit
        ("turn left 120 dgerees", "turn left 120 degrees", ("dgerees", "degrees")),  # 2 edits
        ("stnad up", "stand up", ("stnad", "stand")),  # posture
        ("lie dwon", "lie down", ("dwon", "down")),  # posture
        ("pivto left 45 degrees", "pivot left 45 degrees", ("pivto", "pivot")),  # other verb
    ],
)
def test_a_misspelt_word_of_the_vocabulary_is_read_and_said(typo, clean, read):
    plan = PLANNER.plan(typo)
    assert [(s.skill, s.args) for s in plan.steps] == steps(clean)
    assert f"read '{read[0]}' as '{read[1]}' in '{typo}'" in plan.notes


def test_several_misspellings_in_several_clauses_each_said_once():
    plan = PLANNER.plan("stnad up, wlak forwrd two meters then tunr rigth")
    assert [(s.skill, s.args) for s in plan.steps] == steps(
        "stand up, walk forward two meters then turn right"
    )
    read = [n for n in plan.notes if n.startswith("read ")]
    assert len(read) == 5 and all(n.count("'") == 6 for n in read)


def test_a_word_read_only_one_sensible_way_is_not_ambiguous():
    # 'lfet' is one edit from 'left' and from 'let': only 'left' makes a sentence here.
    assert steps("strafe 1 meter to the lfet") == steps("strafe 1 meter to the left")


def test_words_written_correctly_are_never_rewritten():
    plan = PLANNER.plan("go to the kitchen")  # 'kitchen' is a place, not a typo of anything
    assert [(s.skill, s.args) for s in plan.steps] == [("nav.goto", {"place": "kitchen"})]
    assert not any(n.startswith("read ") for n in plan.notes)


# -- postures with extra words --------------------------------------------------------------------


@pytest.mark.parametrize(
    "text,skill",
    [
        ("lay down on the ground", "body.lie_down"),
        ("lie down right here please", "body.lie_down"),
        ("sit down now", "body.sit"),
        ("kindly sit down where you are", "body.sit"),
        ("stand up straight", "body.stand"),
        ("get up nicely", "body.stand"),
    ],
)
def test_postures_with_words_that_change_nothing(text, skill):
    assert steps(text) == [(skill, {})]


def test_a_posture_keeps_its_duration_among_extra_words():
    assert steps("sit down on the floor for 8 seconds") == [
        ("body.sit", {}),
        ("sys.wait", {"seconds": 8.0}),
    ]


# -- still refused, naming what stands in the way -------------------------------------------------


@pytest.mark.parametrize(
    "text,word",
    [
        ("turn left unless someone is there", "unless"),
        ("walk forward until the wall", "until"),
        ("stand up as soon as the battery is charged", "as soon as"),
        ("if the hallway is clear walk forward 2 meters", "if"),
        ("lie down when the music stops", "when"),
    ],
)
def test_conditions_are_refused_not_half_planned(text, word):
    message = refusal(text)
    assert f"conditions ('{word}')" in message


@pytest.mark.parametrize(
    "text", ["never turn right", "do not walk backward 2 meters", "dont sti down"]
)
def test_negations_are_refused_also_misspelt(text):
    assert "'not'" in refusal(text)


@pytest.mark.parametrize(
    "text,words",
    [
        ("carry the basket to the garage", ["basket", "garage"]),
        ("sit on the sofa", ["sofa"]),
        ("lie down under the piano", ["piano"]),  # "under" it reads (battery below)
        ("walk forward 2 meters and water the plants", ["water", "plants"]),
    ],
)
def test_unknown_words_are_refused_and_named(text, words):
    message = refusal(text)
    for word in words:
        assert f"'{word}'" in message, message
    assert "not a word" in message or "not words" in message


def test_a_word_near_two_words_of_one_meaning_is_read():
    # 'slowy' is one edit from 'slow' and from 'slowly': both make the same plan.
    assert steps("walk forward 1 meter slowy") == steps("walk forward 1 meter slowly")


def test_a_word_that_could_mean_two_things_is_not_guessed():
    message = refusal("lift your paw")  # 'left'? 'list'? neither makes a sentence
    assert "'lift' could be 'left' or 'list'" in message


# -- the property: a typo never changes what is planned ------------------------------------------

SENTENCES = st.builds(
    "{} {} {} {}".format,
    st.sampled_from(["walk", "move", "turn", "rotate", "strafe", "go"]),
    st.sampled_from(["forward", "backward", "left", "right", "clockwise"]),
    st.sampled_from(["two", "three", "seven", "twelve", "forty", "90", "1.5"]),
    st.sampled_from(["meters", "metres", "degrees", "centimeters", "feet", "seconds"]),
) | st.sampled_from(
    ["sit down", "stand up", "lie down", "wait five seconds", "turn around", "walk in a square"]
)


def typo(word: str, kind: str, at: int) -> str:
    at = 1 + at % max(1, len(word) - 2)  # never the first letter (see _spelling)
    if kind == "swap":
        return word[:at] + word[at + 1] + word[at] + word[at + 2 :]
    if kind == "drop":
        return word[:at] + word[at + 1 :]
    return word[:at] + word[at] + word[at:]  # a doubled letter


@settings(max_examples=300, deadline=None)
@given(
    sentence=SENTENCES,
    which=st.integers(0, 3),
    kind=st.sampled_from(["swap", "drop", "double"]),
    at=st.integers(0, 20),
)
@example(sentence="turn left 90 degrees", which=0, kind="swap", at=1)
def test_a_typo_gives_the_same_plan_or_a_refusal_naming_it(sentence, which, kind, at):
    try:
        clean = steps(sentence)
    except PlanningError:
        assume(False)
    words = sentence.split()
    index = which % len(words)
    assume(len(words[index]) >= 4 and words[index].isalpha())
    misspelt = typo(words[index], kind, at)
    assume(misspelt not in spelling.known_words())  # a real word is not a typo
    text = " ".join(words[:index] + [misspelt] + words[index + 1 :])
    try:
        plan = PLANNER.plan(text)
    except PlanningError as exc:
        assert f"'{misspelt}'" in exc.message, exc.message
        return
    assert [(s.skill, s.args) for s in plan.steps] == clean, text
    assert any(f"read '{misspelt}' as" in n for n in plan.notes), plan.notes
