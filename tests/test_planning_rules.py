"""The offline rule planner: kinds of English requests to skill calls."""

from __future__ import annotations

import math
from typing import Any

import pytest

from shadowhound.plan import Plan, PlanningError
from shadowhound.planning.rules import MAX_CHARS, RulePlanner
from shadowhound.robot.go2.api import TRICKS

PLANNER = RulePlanner()

Step = tuple[str, dict[str, Any]]


def steps(text: str, planner: RulePlanner = PLANNER) -> list[Step]:
    return [(s.skill, s.args) for s in planner.plan(text).steps]


def move(d: float, **kw: float) -> Step:
    return ("nav.move", {"distance": d, **kw})


def strafe(d: float, **kw: float) -> Step:
    return ("nav.strafe", {"distance": d, **kw})


def rotate(deg: float) -> Step:
    return ("nav.rotate", {"degrees": deg})


def goto(**kw: Any) -> Step:
    return ("nav.goto", kw)


def trick(name: str) -> Step:
    return ("body.sport", {"trick": name})


def wait(s: float) -> Step:
    return ("sys.wait", {"seconds": s})


STAND, SIT, LIE = ("body.stand", {}), ("body.sit", {}), ("body.lie_down", {})
STOP, STATUS = ("nav.stop", {}), ("sys.status", {})


def square(side: float, turn: float = 90.0, sides: int = 4) -> list[Step]:
    return [move(side), rotate(turn)] * sides


CASES: list[tuple[str, list[Step]]] = [
    # postures
    ("stand up", [STAND]),
    ("Get up!", [STAND]),
    ("rise", [STAND]),
    ("please sit down", [SIT]),
    ("Sit.", [SIT]),
    ("lay down", [LIE]),
    ("lie down now, buddy", [LIE]),
    ("go to sleep", [LIE]),
    ("sit for 10 seconds", [SIT, wait(10.0)]),
    # forward and backward moves, units and number words
    ("go forward 1 meter", [move(1.0)]),
    ("walk forward three meters", [move(3.0)]),
    ("move ahead 2.5 m", [move(2.5)]),
    ("go 3 m ahead", [move(3.0)]),
    ("walk 2 meters forward", [move(2.0)]),
    ("proceed straight for .5 metres", [move(0.5)]),
    ("advance 40 cm", [move(0.4)]),
    ("move forward 50 centimeters", [move(0.5)]),
    ("walk forward 250 mm", [move(0.25)]),
    ("go forward 3 feet", [move(0.9144)]),
    ("go forward 1 foot", [move(0.3048)]),
    ("walk forward 12 inches", [move(0.3048)]),
    ("travel forward 2 yards", [move(1.8288)]),
    ("walk forward twenty five centimeters", [move(0.25)]),
    ("walk forward one hundred meters", [move(100.0)]),
    ("walk forward two point five meters", [move(2.5)]),
    ("walk forward one and a half meters", [move(1.5)]),
    ("walk forward a meter and a half", [move(1.5)]),
    ("walk forward half a meter", [move(0.5)]),
    ("walk forward a metre", [move(1.0)]),
    ("go forward a couple of meters", [move(2.0)]),
    ("half a meter forward", [move(0.5)]),
    ("walk forward 500 meters", [move(500.0)]),
    ("go back 1 meter", [move(-1.0)]),
    ("walk backwards 2 m", [move(-2.0)]),
    ("back up 50 cm", [move(-0.5)]),
    ("reverse two metres", [move(-2.0)]),
    ("go 1 meter backward", [move(-1.0)]),
    ("take a step back", [move(-1.0)]),
    ("walk back and forth 2 meters", [move(2.0), move(-2.0)]),
    # speed words
    ("run forward 3 meters", [move(3.0, speed=0.5)]),
    ("walk forward quickly 2 m", [move(2.0, speed=0.5)]),
    ("slowly walk forward 1 m", [move(1.0, speed=0.2)]),
    ("jog forward 2 meters", [move(2.0)]),
    ("walk forward 2 m at 0.3 m/s", [move(2.0, speed=0.3)]),
    # sideways
    ("step to the left 1 meter", [strafe(1.0)]),
    ("move left 1 m", [strafe(1.0)]),
    ("sidestep right 30 cm", [strafe(-0.3)]),
    ("strafe to your right 2 feet", [strafe(-0.6096)]),
    ("slide left two meters slowly", [strafe(2.0, speed=0.2)]),
    ("shift 1 m to the right", [strafe(-1.0)]),
    # turns
    ("rotate 90 degrees", [rotate(90.0)]),
    ("turn left 90 degrees", [rotate(90.0)]),
    ("turn right 45 degrees", [rotate(-45.0)]),
    ("turn 45° to the right", [rotate(-45.0)]),
    ("rotate clockwise 30 deg", [rotate(-30.0)]),
    ("rotate counter-clockwise by sixty degrees", [rotate(60.0)]),
    ("pivot anticlockwise 10 degrees", [rotate(10.0)]),
    ("turn left", [rotate(90.0)]),
    ("face right", [rotate(-90.0)]),
    ("turn around", [rotate(180.0)]),
    ("about face", [rotate(180.0)]),
    ("do a u-turn", [rotate(180.0)]),
    ("spin right a quarter turn", [rotate(-90.0)]),
    ("turn left a quarter turn", [rotate(90.0)]),
    ("make a half turn", [rotate(180.0)]),
    ("do a full turn", [rotate(360.0)]),
    ("turn all the way around", [rotate(360.0)]),
    ("spin in a full circle to the right", [rotate(-360.0)]),
    ("make a left turn", [rotate(90.0)]),
    ("hang a right", [rotate(-90.0)]),
    ("do a 180", [rotate(180.0)]),
    ("turn 3.14159 rad", [rotate(179.999847693)]),
    # repetition inside a clause
    ("turn left 90 degrees twice", [rotate(90.0)] * 2),
    ("turn right three times", [rotate(-90.0)] * 3),
    ("walk forward 1 m 2 times", [move(1.0)] * 2),
    ("bow x3", [trick("scrape")] * 3),
    ("turn left again", [rotate(90.0)]),
    # sequences
    ("stand up and walk forward 1.5 meters", [STAND, move(1.5)]),
    (
        "walk forward 1 meter then turn left 90 degrees and walk forward 1 meter",
        [move(1.0), rotate(90.0), move(1.0)],
    ),
    ("sit down; stand up. lie down", [SIT, STAND, LIE]),
    ("sit, after that stand up, afterwards dance", [SIT, STAND, trick("dance1")]),
    ("sit down followed by a bow", [SIT, trick("scrape")]),
    ("first stand up, next turn left, finally sit", [STAND, rotate(90.0), SIT]),
    ("turn left 90 then right 45", [rotate(90.0), rotate(-45.0)]),
    ("walk forward 2 m and then 1 m backward", [move(2.0), move(-1.0)]),
    # repeating everything so far
    ("walk forward 1 meter and turn left, repeat 4 times", square(1.0)),
    ("walk forward 1 m then turn right. Do that twice", [move(1.0), rotate(-90.0)] * 2),
    ("bow and then repeat", [trick("scrape")] * 2),
    ("wave then do it again", [trick("hello")] * 2),
    ("sit, stand, repeat 2 more times", [SIT, STAND] * 3),
    # go to
    ("go to position 2, 1", [goto(x=2.0, y=1.0)]),
    ("go to (2, 1)", [goto(x=2.0, y=1.0)]),
    ("go to x 2 y 1", [goto(x=2.0, y=1.0)]),
    ("move to x=3, y=-1", [goto(x=3.0, y=-1.0)]),
    ("navigate to point -1.5, 2", [goto(x=-1.5, y=2.0)]),
    ("go to coordinates 3 0", [goto(x=3.0, y=0.0)]),
    ("go to position two, one", [goto(x=2.0, y=1.0)]),
    ("go to the kitchen", [goto(place="kitchen")]),
    ("walk to the Living Room", [goto(place="living room")]),
    ("head over to the charging dock", [goto(place="charging dock")]),
    ("run into the garage", [goto(place="garage")]),
    ("come back", [goto(place="start")]),
    ("return", [goto(place="start")]),
    ("come back here", [goto(place="start")]),
    ("go back to where you started", [goto(place="start")]),
    ("return to the starting point", [goto(place="start")]),
    ("go home", [goto(place="home")]),
    ("return home", [goto(place="home")]),
    ("go to the origin", [goto(place="home")]),
    ("go to the left", [strafe(1.0)]),
    (
        "move forward 1 meter, turn around, and come back",
        [move(1.0), rotate(180.0), goto(place="start")],
    ),
    # shapes and patrols
    ("walk in a square with 1 meter sides", square(1.0)),
    ("do a 2 m square", square(2.0)),
    ("walk a square of side 1.5 meters", square(1.5)),
    ("walk a square", square(1.0)),
    ("drive in a square clockwise with sides of three feet", square(0.9144, -90.0)),
    ("trace a triangle with 2 m sides", square(2.0, 120.0, 3)),
    (
        "walk a 2 by 1 meter rectangle",
        [move(2.0), rotate(90.0), move(1.0), rotate(90.0)] * 2,
    ),
    ("walk a square twice", square(1.0) * 2),
    ("patrol", [("nav.patrol", {"laps": 1})]),
    ("patrol the perimeter", [("nav.patrol", {"laps": 1})]),
    ("do a patrol round twice", [("nav.patrol", {"laps": 2})]),
    ("patrol the area three times", [("nav.patrol", {"laps": 3})]),
    ("do 2 laps of the perimeter", [("nav.patrol", {"laps": 2})]),
    # waits
    ("wait 2 seconds", [wait(2.0)]),
    ("pause for half a minute", [wait(30.0)]),
    ("wait a second", [wait(1.0)]),
    ("hold for 1.5 min", [wait(90.0)]),
    ("stay for 500 ms", [wait(0.5)]),
    ("sleep for five seconds", [wait(5.0)]),
    ("wait a moment", [wait(1.0)]),
    ("stand still for 3 s", [wait(3.0)]),
    # stop
    ("stop", [STOP]),
    ("halt!", [STOP]),
    ("freeze", [STOP]),
    ("stop moving", [STOP]),
    ("don't move", [STOP]),
    # tricks
    ("say hello", [("voice.say", {"text": "Hello!"}), trick("hello")]),  # aloud, with the wave
    ("wave at me", [trick("hello")]),
    ("greet our visitors", [trick("hello")]),
    ("shake hands", [trick("hello")]),
    ("give me your paw", [trick("hello")]),
    ("do a stretch", [trick("stretch")]),
    ("dance", [trick("dance1")]),
    ("do the second dance", [trick("dance2")]),
    ("dance two", [trick("dance2")]),
    ("wiggle your hips", [trick("wiggle_hips")]),
    ("make a heart", [trick("finger_heart")]),
    ("take a bow", [trick("scrape")]),
    ("strike a pose for the camera", [trick("pose")]),
    ("do the moonwalk", [trick("moonwalk")]),
    ("do a cross-step", [trick("cross_step")]),
    ("recover", [trick("recovery_stand")]),
    ("roll over", [trick("wallow")]),
    ("do a backflip", [trick("backflip")]),
    ("flip backwards", [trick("backflip")]),
    ("do a back flip", [trick("backflip")]),
    ("do a flip", [trick("front_flip")]),
    ("jump", [trick("front_jump")]),
    ("pounce", [trick("front_pounce")]),
    ("flip to the left", [trick("left_flip")]),
    ("do a handstand", [trick("handstand")]),
    ("bound", [trick("bound")]),
    # status and perception
    ("what's your battery level?", [STATUS]),
    ("status", [STATUS]),
    ("where are you", [STATUS]),
    ("how are you doing?", [STATUS]),
    ("report", [STATUS]),
    # more paraphrases
    (
        "Walk forward 2 m, then turn right 90°, walk 1 m and sit.",
        [move(2.0), rotate(-90.0), move(1.0), SIT],
    ),
    ("go forward for five meters and then turn back", [move(5.0), rotate(180.0)]),
    ("walk forward 3 meters and then come back to me", [move(3.0), goto(place="start")]),
    ("go to the café", [goto(place="café")]),
    ("go to room 2", [goto(place="room 2")]),
    ("walk around the perimeter twice", [("nav.patrol", {"laps": 2})]),
    (
        "walk forward 2 meters, wait 3 seconds, walk back 2 meters",
        [move(2.0), wait(3.0), move(-2.0)],
    ),
    ("walk forward 0.5 km", [move(500.0)]),
    ("walk 5 feet 6 inches forward", [move(1.6764)]),
    ("spin 2 full turns", [rotate(720.0)]),
    ("rotate 1 full turn", [rotate(360.0)]),
    ("face backwards", [rotate(180.0)]),
    ("are you ok?", [STATUS]),
    ("perform dance number two", [trick("dance2")]),
    ("lie down for a minute", [LIE, wait(60.0)]),
    ("go to point 3, -2", [goto(x=3.0, y=-2.0)]),
    ("go 2 meters to the left", [strafe(2.0)]),
    ("go to the back door", [goto(place="back door")]),
    # facing a thing, a place or a point: turning in place (nav.face resolves the name)
    ("turn to face the door", [("nav.face", {"place": "door"})]),
    ("face the blue box", [("nav.face", {"place": "blue box"})]),
    ("look at the person", [("nav.face", {"place": "person"})]),
    ("turn towards position 2, 1", [("nav.face", {"x": 2.0, "y": 1.0})]),
    ("turn so you are facing the kitchen", [("nav.face", {"place": "kitchen"})]),
    ("turn your head to the red ball", [("nav.face", {"place": "red ball"})]),
    ("turn to the left", [rotate(90.0)]),
    # questions about its own travel: answered from the odometer, nothing moves
    ("how far have you walked?", [STATUS]),
    ("how long have you been walking?", [STATUS]),
    ("how much distance have you covered", [STATUS]),
    ("walk forward 1 meter then tell me how far you walked", [move(1.0), STATUS]),
    ("walk forward 1 meter and turn right, four times", [move(1.0), rotate(-90.0)] * 4),
    # fillers
    ("Hey dog, could you please turn right?", [rotate(-90.0)]),
    ("I want you to go ahead and walk forward 2 meters now", [move(2.0)]),
    ("Robot, sit down please.", [SIT]),
]


@pytest.mark.parametrize(("text", "expected"), CASES, ids=[c[0] for c in CASES])
def test_phrasings(text: str, expected: list[Step]) -> None:
    got = steps(text)
    assert [s for s, _ in got] == [s for s, _ in expected]
    for (_, args), (_, want) in zip(got, expected, strict=False):
        assert args.keys() == want.keys()
        for key, value in want.items():
            if isinstance(value, float):
                assert args[key] == pytest.approx(value, abs=1e-6), key
                assert isinstance(args[key], float)
            else:
                assert args[key] == value


@pytest.mark.parametrize(
    ("text", "skill"),
    [
        ("what do you see?", "perception.describe"),
        ("tell me what you see", "perception.describe"),
        ("describe your surroundings", "perception.describe"),
        ("what's in front of you", "perception.describe"),
        ("is there anything ahead?", "perception.describe"),
        ("take a look", "perception.describe"),
        ("look ahead", "perception.describe"),
        ("look at the view", "perception.describe"),
        ("look around", "perception.look_around"),
        ("scan the room", "perception.look_around"),
    ],
)
def test_questions_pass_the_clause(text: str, skill: str) -> None:
    plan = PLANNER.plan(text)
    assert [s.skill for s in plan.steps] == [skill]
    assert plan.steps[0].args == {"question": text.rstrip("?")}


def test_plan_fields_labels_and_notes() -> None:
    plan = PLANNER.plan("Stand up, then walk forward and turn left twice")
    assert isinstance(plan, Plan)
    assert plan.planner == "offline" and plan.text.startswith("Stand up")
    assert [s.label for s in plan.steps] == [
        "Stand up", "walk forward", "turn left twice", "turn left twice"
    ]  # fmt: skip
    assert "no distance given for 'walk forward': used 1 m" in plan.notes
    assert any("no angle given for 'turn left twice'" in n for n in plan.notes)
    assert PLANNER.plan("walk forward 2 m").notes == []


def test_defaults_come_from_the_constructor() -> None:
    planner = RulePlanner(
        default_distance=0.5, default_turn_degrees=45.0, default_wait=3.0, default_square_side=2.0
    )
    assert steps("walk forward", planner) == [move(0.5)]
    assert steps("turn right", planner) == [rotate(-45.0)]
    assert steps("wait", planner) == [wait(3.0)]
    assert steps("walk a square", planner) == square(2.0)
    assert steps("turn around", planner) == [rotate(180.0)]


def test_context_is_ignored() -> None:
    assert PLANNER.plan("sit", context={"battery": 0.1}).steps == PLANNER.plan("sit").steps


def test_every_trick_name_is_understood() -> None:
    for name in TRICKS:
        assert steps(f"do {name.replace('_', ' ')}") == [trick(name)], name


def test_square_ends_where_it_started() -> None:
    x = y = yaw = 0.0
    for skill, args in steps("walk in a square with 1.5 meter sides clockwise"):
        if skill == "nav.move":
            x += args["distance"] * math.cos(math.radians(yaw))
            y += args["distance"] * math.sin(math.radians(yaw))
        else:
            yaw += args["degrees"]
    assert (x, y, yaw % 360) == pytest.approx((0.0, 0.0, 0.0), abs=1e-9)


@pytest.mark.parametrize("text", ["", "   ", "\n\t"])
def test_empty_mission(text: str) -> None:
    with pytest.raises(PlanningError, match="The mission is empty"):
        PLANNER.plan(text)


def test_too_long() -> None:
    with pytest.raises(PlanningError, match=str(MAX_CHARS)):
        PLANNER.plan("sit and " * 300)


@pytest.mark.parametrize(
    "text",
    [
        "blorp the zanzibar",
        "please",
        "fly to the moon",
        "turn left 2 meters",
        "walk forward 5 seconds",
        "wait 3 meters",
        "don't turn left",
        "walk forward left",
        "come here",
        "go to position 2",
        "come here",
        "take two steps forward",
        "walk forward 1e999 meters",
        "walk forward " + "9" * 400 + " meters",
        "turn left 1.5 times",
        "repeat",
        "walk a 2 m rectangle",
    ],
)
def test_not_understood(text: str) -> None:
    with pytest.raises(PlanningError):
        PLANNER.plan(text)


def test_failure_says_what_was_understood_and_what_not() -> None:
    with pytest.raises(PlanningError) as info:
        PLANNER.plan("stand up, blorp the zanzibar and turn left")
    err = info.value
    assert err.understood == ["stand up", "turn left 90 degrees"]
    assert err.not_understood == ["blorp the zanzibar"]
    assert '"blorp the zanzibar"' in err.message
    assert "I understood: stand up; turn left 90 degrees." in err.message
    assert "I can stand, sit, lie down" in err.message


def test_reason_is_given_for_a_known_kind() -> None:
    with pytest.raises(PlanningError, match="angle"):
        PLANNER.plan("turn left 2 meters")


def test_repeats_are_bounded() -> None:
    with pytest.raises(PlanningError, match="limit"):
        PLANNER.plan("turn left 1000000 times")


@pytest.mark.parametrize("value", [None, 42, b"sit", ["sit"], 3.5])
def test_non_text_is_a_planning_error(value: Any) -> None:
    with pytest.raises(PlanningError):
        PLANNER.plan(value)


def test_a_five_clause_sentence_is_five_steps_and_planning_it_again_gives_the_same_plan() -> None:
    """How fast the offline planner is, is bench/bench_core.py's figure (a five-step sentence,
    under 1 ms), not a test's: a loaded machine makes any time."""
    text = "stand up, walk forward three meters, turn left 90 degrees, go to the kitchen, sit down"
    plan = PLANNER.plan(text)
    assert [s.skill for s in plan.steps] == [
        "body.stand",
        "nav.move",
        "nav.rotate",
        "nav.goto",
        "body.sit",
    ]
    assert PLANNER.plan(text).steps == plan.steps  # nothing carried over between calls


hypothesis = pytest.importorskip("hypothesis")
st = hypothesis.strategies
_WORD_TEXT = (
    "walk turn left 2 meters and then , twice go to the x y -1.5 repeat half a square sit please"
    " ° by times one hundred point five couple of back forth 3x2 rectangle patrol laps wait for"
    " seconds do that again 1/2 ( ) = : . ? don't at m/s slowly"
)
WORDS = _WORD_TEXT.split(" ")


@hypothesis.settings(max_examples=300, deadline=None)
@hypothesis.given(st.one_of(st.text(max_size=300), st.lists(st.sampled_from(WORDS)).map(" ".join)))
def test_random_text_gives_a_plan_or_a_planning_error(text: str) -> None:
    try:
        plan = PLANNER.plan(text)
    except PlanningError as exc:
        assert exc.message
        return
    assert plan.steps
    for step in plan.steps:
        for value in step.args.values():
            if isinstance(value, float):
                assert math.isfinite(value)
