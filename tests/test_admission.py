"""The rules a mission meets before planning (shadowhound.admission): text limits, e-stop.

The agent, its dry run and the early checks of the web API and the MCP tools all use the one
rule; these tests hold them to it.
"""

from __future__ import annotations

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.admission import ESTOP_LATCHED, mission_text_problem
from shadowhound.memory.places import PlaceBook, known_places
from shadowhound.robot_config import RobotId

LIMIT = 20


@pytest.fixture(scope="module")
def agent() -> RobotAgent:
    settings = ShadowHoundConfig(agent={"max_mission_chars": LIMIT})
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(time_scale=0.0), settings=settings))
    agent.initialize()
    return agent


def test_the_rule_names_what_was_wrong_and_what_is_allowed() -> None:
    assert mission_text_problem(42, LIMIT) == "the mission must be a string, got int"
    assert "is empty; say what the robot should do" in str(mission_text_problem(" \n\t", LIMIT))
    assert mission_text_problem("x" * 21, LIMIT) == (
        "the mission is 21 characters long; the limit is 20 (agent.max_mission_chars)"
    )
    assert mission_text_problem("x" * 20, LIMIT) is None
    assert str(mission_text_problem("", LIMIT, "the command")).startswith("the command is empty")


@settings(max_examples=40, deadline=None)
@given(text=st.text(alphabet=" \t\nstandup", max_size=2 * LIMIT))
def test_the_run_and_the_dry_run_refuse_exactly_what_the_rule_refuses(
    agent: RobotAgent, text: str
) -> None:
    problem = mission_text_problem(text, LIMIT)
    for result in (agent.dry_run(text), agent.execute_mission(text)):
        if problem:
            assert not result.success and problem in result.response
        else:  # planned (or not understood), never refused by the text rule
            assert "is empty" not in result.response
            assert "characters long" not in result.response


def test_a_latched_estop_refuses_with_the_one_message(agent: RobotAgent) -> None:
    agent.estop()
    try:
        refused = agent.execute_mission("stand up")
        assert not refused.success and ESTOP_LATCHED in refused.response
        assert agent.dry_run("stand up").success  # a dry run moves nothing: still allowed
    finally:
        agent.release_estop()


# -- places: the profile's and the taught ones, merged once ----------------------------------


def test_taught_places_join_the_profiles_and_win_a_shared_name() -> None:
    book = PlaceBook(robot=RobotId("sim"))
    book.remember("Kitchen", 4.0, 1.0, 0.5)
    book.remember("the porch", -1.0, 2.0, 0.0)
    known = known_places({"kitchen": (3.0, 2.0), "lab": (1.0, 1.0)}, book)
    assert list(known) == ["lab", "kitchen", "porch"]  # the profile's, then taught ones
    assert known["lab"].source == "profile" and known["lab"].yaw is None
    assert known["kitchen"].position == (4.0, 1.0) and known["kitchen"].source == "taught"
    assert known["porch"].yaw == 0.0


def test_every_reader_of_places_sees_the_taught_ones() -> None:
    from shadowhound.mcp.desk import McpDesk

    settings = ShadowHoundConfig(places={"lab": [1.0, 1.0]})
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(time_scale=0.0), settings=settings))
    assert agent.execute_mission("walk forward 1 meter, remember this spot as the porch").success
    listed = agent.execute_mission("list the places you know")
    assert "lab (1.00, 1.00)" in listed.response
    assert "porch (1.00, 0.00, taught)" in listed.response
    assert agent.execute_mission("go to the lab then go to the porch").success
    assert agent.robot.get_state().x == pytest.approx(1.0, abs=0.02)
    desk = McpDesk(agent)
    try:
        assert set(desk.places()) == {"lab", "porch"}
        assert desk.places()["porch"]["x"] == pytest.approx(1.0, abs=0.02)
    finally:
        desk.close()
    agent.cleanup()
