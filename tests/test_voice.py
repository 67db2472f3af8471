"""The robot's voice: the `voice.say` skill, what it may say (cleaned, cut, rate-limited), and
the offline planner's reading of requests to speak."""

from __future__ import annotations

import unicodedata

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.events import MissionEvent, Spoken
from shadowhound.plan import PlanningError, SkillCall
from shadowhound.planning.rules import RulePlanner
from shadowhound.speech import MAX_TEXT, Voice, clean_speech

PLANNER = RulePlanner()


def make(**safety: object) -> tuple[RobotAgent, SimRobot, list[Spoken]]:
    settings = ShadowHoundConfig(safety=safety) if safety else ShadowHoundConfig()
    robot = SimRobot(time_scale=0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    heard: list[Spoken] = []

    def listen(event: MissionEvent) -> None:
        if isinstance(event, Spoken):
            heard.append(event)

    agent.add_listener(listen)
    return agent, robot, heard


def plan(text: str) -> list[tuple[str, dict[str, object]]]:
    return [(s.skill, s.args) for s in PLANNER.plan(text).steps]


def speakable(text: str) -> bool:
    return not any(unicodedata.category(ch).startswith("C") for ch in text)


# -- what may be said -------------------------------------------------------------------------


@settings(max_examples=300, deadline=None)
@given(text=st.text(min_size=1, max_size=MAX_TEXT), limit=st.integers(10, 500))
def test_any_text_is_spoken_within_the_limit_and_without_control_characters(
    text: str, limit: int
) -> None:
    agent, robot, heard = make(max_speech_chars=limit)
    result = agent.run_plan([SkillCall("voice.say", {"text": text})])
    if not clean_speech(text, MAX_TEXT):  # nothing but spaces and control characters
        assert not result.success and "no words to say" in result.response
        assert robot.spoken == []
        return
    assert result.success, result.response
    [said] = robot.spoken
    assert 0 < len(said) <= limit and speakable(said) and said == said.strip()
    assert [e.text for e in heard] == [said]


def test_a_long_answer_is_cut_at_a_word_and_says_so() -> None:
    words = "the quick brown fox jumps over the lazy dog " * 10
    agent, robot, _ = make(max_speech_chars=50)
    result = agent.run_plan([SkillCall("voice.say", {"text": words})])
    assert result.success
    [said] = robot.spoken
    assert len(said) <= 50 and said.endswith("...") and words.startswith(said[:-3])
    assert "cut to fit safety.max_speech_chars" in result.steps[0].output


@pytest.mark.parametrize(
    ("args", "why"),
    [
        ({"text": ""}, "at least 1 character"),
        ({"text": " \n\t\x07 "}, "no words to say"),
        ({"text": "x" * (MAX_TEXT + 1)}, f"at most {MAX_TEXT} characters"),
        ({"text": 42}, "valid string"),
        ({"text": ["hello"]}, "valid string"),
        ({"words": "hello"}, "unknown argument 'words'; allowed arguments: text"),
    ],
)
def test_bad_text_is_refused_before_anything_runs_naming_what_is_allowed(
    args: dict[str, object], why: str
) -> None:
    agent, robot, heard = make()
    result = agent.run_plan([SkillCall("voice.say", args)])
    assert not result.success and why in result.response, result.response
    assert "voice.say" in result.response and robot.spoken == [] and heard == []


def test_over_the_rate_the_words_are_shown_not_spoken_and_the_mission_goes_on() -> None:
    agent, robot, heard = make(max_speech_per_minute=2)
    calls = [SkillCall("voice.say", {"text": f"number {i}"}) for i in range(3)]
    result = agent.run_plan([*calls, SkillCall("nav.move", {"distance": 0.5})])
    assert result.success, result.response
    assert robot.spoken == ["number 0", "number 1"]
    assert "did not say" in result.steps[2].output and "max_speech_per_minute" in (
        result.steps[2].output
    )
    assert [(e.text, e.aloud) for e in heard][-1] == ("number 2", False)
    assert robot.get_state().x == pytest.approx(0.5, abs=0.05)  # motion was not held up
    agent.run_plan([SkillCall("sys.wait", {"seconds": 60})])  # a minute on the robot's clock
    assert agent.run_plan([SkillCall("voice.say", {"text": "again"})]).success
    assert robot.spoken[-1] == "again"


def test_zero_a_minute_means_never_aloud() -> None:
    agent, robot, heard = make(max_speech_per_minute=0)
    result = agent.run_plan([SkillCall("voice.say", {"text": "hello"})])
    assert result.success and robot.spoken == []
    assert heard[0].why_silent.startswith("speaking aloud is off")


def test_the_limits_are_bounded_in_the_profile() -> None:
    for bad in ({"max_speech_chars": 5}, {"max_speech_chars": 501}, {"max_speech_per_minute": 61}):
        with pytest.raises(ValueError, match="max_speech"):
            ShadowHoundConfig(safety=bad)


def test_a_robot_without_a_voice_is_said_so() -> None:
    class Mute:
        def now(self) -> float:
            return 0.0

        def say(self, text: str) -> None:
            from shadowhound.robot.base import RobotError

            raise RobotError("this robot has no voice")

    saying = Voice(ShadowHoundConfig()).speak(Mute(), "hello")
    assert not saying.aloud and saying.why_silent == "this robot has no voice"


def test_without_text_it_says_the_missions_latest_answer() -> None:
    agent, robot, _ = make()
    result = agent.execute_mission("tell me what you see and say it out loud")
    assert result.success, result.response
    [said] = robot.spoken
    assert said.startswith("In view: red ball") and len(said) <= 200
    assert result.steps[-1].output == "said the answer aloud (cut to fit safety.max_speech_chars)"


def test_without_text_and_without_an_answer_the_step_fails_clearly() -> None:
    agent, robot, _ = make()
    result = agent.run_plan([SkillCall("voice.say", {})])
    assert not result.success and "nothing to say" in result.response
    assert robot.spoken == []


# -- the offline planner --------------------------------------------------------------------


SAY = "voice.say"
WAVE = ("body.sport", {"trick": "hello"})


@pytest.mark.parametrize(
    ("text", "expected"),
    [
        ("say hello", [(SAY, {"text": "Hello!"}), WAVE]),
        ("please say hi", [(SAY, {"text": "Hi!"}), WAVE]),
        ("say good morning", [(SAY, {"text": "Good morning!"}), WAVE]),
        ("Say good night, robot", [(SAY, {"text": "Good night!"}), WAVE]),
        ("say hello twice", [(SAY, {"text": "Hello!"}), WAVE] * 2),
        ('say "Dinner is ready"', [(SAY, {"text": "Dinner is ready"})]),
        ("announce that the kitchen is clear", [(SAY, {"text": "That the kitchen is clear"})]),
        ("Say: I am on my way", [(SAY, {"text": "I am on my way"})]),
        ("shout watch out", [(SAY, {"text": "Watch out"})]),
    ],
)
def test_words_to_say_keep_their_case_and_greetings_come_with_the_wave(
    text: str, expected: list[tuple[str, dict[str, object]]]
) -> None:
    assert plan(text) == expected


@pytest.mark.parametrize(
    ("text", "asked"),
    [
        ("say what you see", "perception.describe"),
        ("tell me what you see and say it out loud", "perception.describe"),
        ("what do you see? say it aloud", "perception.describe"),
        ("describe the room out loud", "perception.describe"),
        ("say where you are", "sys.status"),
        ("tell me your battery level out loud", "sys.status"),
        ("say how far you have walked", "sys.status"),
    ],
)
def test_a_question_to_answer_aloud_is_asked_then_its_answer_said(text: str, asked: str) -> None:
    got = plan(text)
    assert [s for s, _ in got] == [asked, SAY] and got[-1][1] == {}


def test_speaking_goes_with_other_requests_in_one_mission() -> None:
    got = plan("walk forward 1 meter, say I am here, then turn left")
    assert [s for s, _ in got] == ["nav.move", SAY, "nav.rotate"]
    assert got[1][1] == {"text": "I am here"}


def test_saying_an_answer_with_none_before_it_is_refused_with_what_to_ask() -> None:
    with pytest.raises(PlanningError, match="nothing before it gives an answer to say"):
        PLANNER.plan("say it out loud")


def test_say_hello_on_the_simulator_speaks_and_waves() -> None:
    agent, robot, heard = make()
    result = agent.execute_mission("go to the blue box and say good morning")
    assert result.success, result.response
    assert robot.spoken == ["Good morning!"] and heard[0].step == len(result.steps) - 1
    assert any(c.kind == "trick" and c.value == "hello" for c in robot.commands)
    assert 'said "Good morning!" aloud' in result.response


def test_tell_me_without_out_loud_answers_on_screen_only() -> None:
    assert [s for s, _ in plan("tell me what you see")] == ["perception.describe"]
    assert [s for s, _ in plan("tell me where you are")] == ["sys.status"]


def test_a_greeting_to_someone_is_the_greeting_and_speaking_to_someone_is_not_words() -> None:
    assert plan("please say good morning to everyone") == [(SAY, {"text": "Good morning!"}), WAVE]
    with pytest.raises(PlanningError, match="say things aloud"):
        PLANNER.plan("speak to me")


def test_control_characters_go_and_do_not_count_toward_the_cut() -> None:
    agent, robot, _ = make(max_speech_chars=10)
    result = agent.run_plan([SkillCall("voice.say", {"text": "ab\x00\x07\x1b\x7f\u200bcd\n"})])
    assert result.success and robot.spoken == ["ab cd"]
    assert result.steps[0].output == 'said "ab cd" aloud'


def test_with_speak_results_the_robot_says_each_outcome_once() -> None:
    """speech.speak_results: a mission's result, a refusal and a chat answer are said on the
    robot's speaker (the simulator's record of what it said); a mission that spoke itself is
    not said over; a dry run says nothing."""
    settings = ShadowHoundConfig(speech={"speak_results": True})
    settings.memory.enabled = False
    robot = SimRobot(time_scale=0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    done = agent.execute_mission("walk forward 0.5 meters")
    assert robot.spoken == [done.response] == ["Done: moved 0.50 m forward."]
    refused = agent.execute_mission("fly to the moon")
    said = robot.spoken[-1]  # cut at a word to safety.max_speech_chars
    assert not refused.success and refused.response.startswith(said.removesuffix("..."))
    assert len(said) <= settings.safety.max_speech_chars
    agent.execute_mission("say hello")
    assert robot.spoken[-1] == "Hello!"  # its own words, not "said ... aloud" after them
    before = len(robot.spoken)
    agent.dry_run("walk forward 1 meter")
    assert len(robot.spoken) == before
    answer = agent.chat("where are you?")
    assert robot.spoken[-1] == answer
    off = SimRobot(time_scale=0)
    RobotAgent(RobotAgentConfig(robot=off, settings=ShadowHoundConfig())).execute_mission(
        "walk forward 0.5 meters"
    )
    assert off.spoken == []  # off by default
