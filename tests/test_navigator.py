"""The navigation setting (auto | nav2 | direct) on a robot without a navigator, Nav2's error
codes in words, and the path follower of the sim driver's navigate_to_pose server, driving the
simulator (the DDS side is tests/ros/test_go2_nav2.py)."""

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.config import ConfigError, load_config
from shadowhound.robot.navigator import nav2_error_words
from shadowhound.robot.sim.scene import DEFAULT_WORLD
from shadowhound.robot.sim.sensors import penetration, scene_belief
from shadowhound.state import Pose2D
from shadowhound.world import plan_route
from shadowhound.world.follow import PathFollower

BODY = 0.35


def agent_with(navigation: str) -> tuple[RobotAgent, SimRobot]:
    robot = SimRobot(time_scale=0.0)
    agent = RobotAgent(
        RobotAgentConfig(robot=robot, settings=ShadowHoundConfig(navigation=navigation))
    )
    agent.initialize()
    return agent, robot


def test_the_simulator_declares_no_navigator() -> None:
    assert SimRobot(time_scale=0.0).navigator() is None


@pytest.mark.parametrize("navigation", ["auto", "direct"])
def test_without_a_navigator_auto_and_direct_walk_the_projects_path(navigation: str) -> None:
    agent, robot = agent_with(navigation)
    result = agent.execute_mission("go to x=4, y=0")
    assert result.success, result.response
    st_ = robot.get_state()
    assert math.hypot(st_.x - 4.0, st_.y) < 0.01


def test_nav2_required_without_a_navigator_fails_clearly_and_does_not_move() -> None:
    agent, robot = agent_with("nav2")
    result = agent.execute_mission("go to x=4, y=0")
    assert not result.success and not robot.received_motion
    assert (
        "navigation is 'nav2', but the robot 'sim-go2' has no Nav2 navigator (only a Go2 on "
        "ROS 2 has one); set navigation: auto or direct"
    ) in result.response


def test_navigation_is_checked_in_the_config() -> None:
    with pytest.raises(ConfigError, match="navigation"):
        load_config("offline", {"navigation": "nav3"})
    assert load_config("offline").navigation == "auto"


@pytest.mark.parametrize(
    ("code", "message", "words"),
    [
        (
            206,
            "",
            "the goal is occupied on the costmap (inside an obstacle or its inflation) "
            "(Nav2 error code 206)",
        ),
        (
            105,
            "  stuck   behind a chair ",
            "the robot failed to make progress along the path "
            "(Nav2 error code 105): stuck behind a chair",
        ),
        (9999, "", "navigation failed (Nav2 error code 9999)"),
        (0, "aborted by the BT", "navigation failed: aborted by the BT"),
    ],
)
def test_nav2_error_codes_in_words(code: int, message: str, words: str) -> None:
    assert nav2_error_words(code, message) == words


def drive(robot: SimRobot, follower: PathFollower, seconds: float = 120.0) -> bool:
    """Run the follower at 10 Hz on the simulator; True when it reports the goal reached."""
    for _ in range(int(seconds / 0.1)):
        command = follower.command(robot.get_state().pose)
        if command is None:
            robot.stop()
            return True
        robot.send_velocity(*command)
        robot.sleep(0.1)
    return False


@settings(max_examples=15, deadline=None)
@given(x=st.floats(-4.5, 4.5), y=st.floats(-4.5, 4.5), yaw=st.floats(-math.pi, math.pi))
def test_the_follower_reaches_planned_goals_without_touching_anything(
    x: float, y: float, yaw: float
) -> None:
    robot = SimRobot(time_scale=0.0)
    belief = scene_belief(DEFAULT_WORLD, BODY)
    cell = belief.grid.cell_of(x, y)
    if belief.inflated.is_blocked(cell):
        return  # the planner refuses such goals (tests/test_navigation.py)
    path = plan_route(belief, (0.0, 0.0), (x, y))
    follower = PathFollower([*path.waypoints[1:], (x, y)], yaw)
    assert drive(robot, follower)
    end = robot.get_state()
    assert math.hypot(end.x - x, end.y - y) <= follower.tolerance + 0.01
    assert abs(math.remainder(end.yaw - yaw, math.tau)) <= follower.yaw_tolerance + 0.01
    assert max(penetration(robot.world, px, py, BODY)[0] for _t, px, py in robot.true_path) == 0.0
    assert follower.remaining(Pose2D(end.x, end.y, end.yaw)) <= follower.tolerance + 0.01
