"""perception.describe and perception.look_around without a vision model: what is seen comes
first, what a vision model would add is said once, and the command line says it once."""

from __future__ import annotations

import subprocess
import sys
import threading
import time

import pytest

from shadowhound import SkillCall, default_registry
from shadowhound.config import ShadowHoundConfig
from shadowhound.skills import PlanEnv, SkillContext
from shadowhound.skills.sense import describe_frame
from shadowhound.state import CameraFrame
from tests.test_skills import run

VIEWS = ("Ahead: ", "To my left: ", "Behind me: ", "To my right: ")


@pytest.fixture
def registry():
    return default_registry()


def test_describe_leads_with_what_is_in_view(registry, robot):
    out = run(registry, robot, "perception.describe")
    assert out.startswith("In view: red ball about 3.0 m ahead; blue box about 3.2 m"), out
    assert out.count("vision model") == 1 and "llm.vision" in out
    assert out.count("160x120") == 1 and out.index("160x120") > out.index("white fridge")
    assert len(out) < 400


def test_look_around_gives_each_view_its_own_line_and_the_note_once(registry, robot):
    out = run(registry, robot, "perception.look_around")
    lines = out.splitlines()
    assert [line[: len(v)] for line, v in zip(lines, VIEWS, strict=False)] == list(VIEWS), out
    assert lines[0] == "Ahead: red ball about 3.0 m ahead; blue box about 3.2 m 39 degrees to " + (
        "the left; green plant about 4.7 m 32 degrees to the right; white fridge about 5.8 m "
        "34 degrees to the left."
    )
    assert "yellow chair" in lines[1] and "charging dock" in lines[2] and "person" in lines[3]
    assert out.count("vision model") == 1 and out.count("160x120") <= 1
    assert len(lines) == 5 and all(len(line) < 220 for line in lines), out


def test_a_camera_frame_without_sightings_says_what_it_has_once():
    frame = CameraFrame(b"\xff\xd8jpeg", 64, 48, "jpeg", stamp=time.time(), source="camera")
    out = describe_frame(frame, "what do you see?")
    assert out.startswith("I have a 64x48 JPEG frame from the camera"), out
    assert out.count("vision model") == 1 and "llm.vision" in out


def test_no_camera_image_is_said_once_for_a_look_around(registry, robot):
    call = registry.validate(SkillCall("perception.look_around", {}))
    env = PlanEnv(ShadowHoundConfig(), robot.get_state().pose)
    # A camera that has sent nothing yet (a robot's camera topic before its first frame).
    ctx = SkillContext(robot, env, threading.Event(), camera=lambda: None)
    ctx.start_clock(call.skill.timeout_for(call.args, env))
    out = call.skill.run(ctx, call.args)
    assert out.count("no camera image") == 1, out


def test_the_mission_response_keeps_the_views_apart(agent):
    result = agent.execute_mission("look around")
    assert result.success, result.response
    lines = result.response.splitlines()
    assert [line.split(":")[0] + ": " for line in lines[:4]] == list(VIEWS), result.response
    assert result.response.count("vision model") == 1


def test_chat_answers_what_it_sees_first(agent):
    answer = agent.chat("what do you see?")
    assert answer.startswith("In view: red ball about 3.0 m ahead"), answer
    assert answer.count("vision model") == 1


@pytest.mark.parametrize(
    ("mission", "said"),
    [("what do you see?", "red ball about 3.0 m ahead"), ("look around", "yellow chair")],
)
def test_the_command_line_says_the_answer_once(mission, said):
    """Progress (stderr) and the response (stdout) together, as a terminal shows them."""
    proc = subprocess.run(
        [sys.executable, "-m", "shadowhound", "run", mission],
        stdout=subprocess.PIPE,
        stderr=subprocess.STDOUT,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 0, proc.stdout
    assert proc.stdout.count(said) == 1, proc.stdout
    assert proc.stdout.count("vision model") == 1, proc.stdout


def test_with_a_vision_model_the_model_answers():
    frame = CameraFrame(b"png", 160, 120, "png", source="simulator")
    out = describe_frame(frame, "what is that?", lambda f, q: f"A red ball ({q})")
    assert out == "A red ball (what is that?)"
