"""An honest Go2 on a loaded machine: the checks against lying odometry do not cry wolf
(issue 32), judged by the truth.

The robot is `LoadedRobot` (tests/loaded_robot.py): the late-odometry Go2 of
test_go2_closed_loop whose control loop, ROS thread and driver stall at given moments, exactly,
as on a 2-core machine running SLAM, Nav2 and a detector beside ShadowHound (or CI's workers).
Its odometry never lies. The issue's false failures, each from one stall:

- "stopped 8 degrees short of the turn: it was commanded 94 degrees ... odometry disagrees with
  the motion": the driver stalled as the turn began; its commands ran ahead of the robot;
- "odometry shows the turn done (90 degrees), yet its commands turned the robot 82": the driver
  stalled as the turn slowed, so the robot turned on at speed while its commands slowed;
- "no odometry on odom for 0.6 s": ShadowHound itself stalled, odometry waiting in its queue.

The lies of tests/test_odometry_faults.py are still caught on a quiet machine exactly as before
(that file runs unchanged); here, a lie larger than the stalls seen explain is caught under load.
"""

from __future__ import annotations

import math
import random

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shadowhound import RobotAgent, RobotAgentConfig
from shadowhound.config import ShadowHoundConfig
from shadowhound.robot.go2.motion import GO2_MOTION
from shadowhound.sim_driver.faults import Faults
from shadowhound.skills.bounds import leg_margin, turn_margin
from shadowhound.skills.context import ODOMETRY_RETURN
from tests.loaded_robot import WHO, LoadedRobot, Stall


def go2_agent(robot: LoadedRobot) -> RobotAgent:
    settings = ShadowHoundConfig(robot="go2")
    settings.motion = settings.motion.model_copy(update=GO2_MOTION)
    settings.memory.enabled = False
    return RobotAgent(RobotAgentConfig(robot=robot, settings=settings))


def turned(robot: LoadedRobot, start_yaw: float) -> float:
    return math.degrees(math.remainder(robot.sim.get_state().yaw - start_yaw, math.tau))


@pytest.mark.parametrize(
    ("stall", "ci_said"),
    [
        (Stall("driver", 0.05, 0.45), "stopped 8 degrees short of the turn"),
        (Stall("driver", 1.8, 0.4), "odometry shows the turn done (90 degrees), yet its"),
    ],
)
def test_a_turn_whose_commands_the_driver_held_up_succeeds(stall: Stall, ci_said: str) -> None:
    """CI's failures, said as CI said them on the old code: the driver stalled 0.4 s as the
    turn began (its commands ran ahead of the robot), or as it slowed (the robot turned on)."""
    robot = LoadedRobot([stall])
    start = robot.sim.get_state()
    result = go2_agent(robot).execute_mission("turn left 90 degrees")
    robot.sleep(2.0)
    assert result.success, (ci_said, result.response)
    assert abs(turned(robot, start.yaw) - 90.0) <= 5.0, turned(robot, start.yaw)


def test_a_start_the_driver_held_up_unseen_in_odometry_succeeds_on_a_loaded_machine() -> None:
    """Only the driver's command path stalls (its executor busy with a detector's work), its
    odometry goes out as ever: the stream shows no stall then, but odometry shows the turn start
    0.3 s later than the latency says, and ShadowHound's own ROS thread stalled a moment later
    (the machine is loaded): that start's commands are allowed for (it failed: "stopped 10
    degrees short of the turn")."""
    robot = LoadedRobot([Stall("commands", 0.0, 0.3), Stall("receiver", 0.8, 0.1)])
    start = robot.sim.get_state()
    result = go2_agent(robot).execute_mission("turn left 90 degrees")
    robot.sleep(2.0)
    assert result.success, result.response
    assert abs(turned(robot, start.yaw) - 90.0) <= 5.0, turned(robot, start.yaw)


def test_a_late_start_on_a_quiet_machine_is_allowed_nothing() -> None:
    """With no stall of the link seen, a start odometry shows late is the robot's own, or the
    shape of a lie: the commands go no further than the margin, as before."""
    robot = LoadedRobot([Stall("commands", 0.0, 0.3)])
    start = robot.sim.get_state()
    robot.truths.clear()
    result = go2_agent(robot).execute_mission("turn left 90 degrees")
    robot.sleep(2.0)
    most = max(math.degrees(math.remainder(t.yaw - start.yaw, math.tau)) for t in robot.truths)
    assert most <= 90.0 + 5.0, (most, result.response)
    assert not result.success or abs(turned(robot, start.yaw) - 90.0) <= 5.0, result.response


def test_shadowhound_stalling_mid_walk_stops_the_robot_and_goes_on() -> None:
    """ShadowHound gets no CPU for 0.6 s mid-walk: its control loop wakes to odometry 0.6 s old
    (the rest waits in its queue), which failed the step ("no odometry on odom for 0.6 s").
    The robot stops at once, as it did, and the walk goes on once odometry is there."""
    robot = LoadedRobot([Stall("process", 1.5, 0.6)])
    start = robot.sim.get_state()
    result = go2_agent(robot).execute_mission("walk forward 1 meter")
    robot.sleep(2.0)
    assert result.success, result.response
    assert "stopped while odometry paused" in result.response, result.response
    assert abs(robot.sim.get_state().x - start.x - 1.0) <= 0.05


def test_odometry_that_stays_away_still_fails_the_step_with_the_robot_stopped() -> None:
    """A stream that stops for good (the driver gone) is not waited on for long: the robot
    stops at once, and the step fails naming the stale stream after ODOMETRY_RETURN at rest."""
    robot = LoadedRobot([Stall("receiver", 1.5, 1000.0)])
    start = robot.sim.get_state()
    result = go2_agent(robot).execute_mission("walk forward 2 meters")
    robot.sleep(3.0)
    assert not result.success
    assert "no odometry on odom for" in result.response, result.response
    assert f"it did not come back within {ODOMETRY_RETURN:g} s" in result.response
    walked = robot.sim.get_state().x - start.x
    assert 0.3 < walked < 1.0, walked  # stopped where it was when odometry went away
    assert robot.sim.get_state().vx == 0.0


def test_a_control_loop_stalled_past_the_end_of_its_leg_comes_back() -> None:
    """ShadowHound's control loop stalls 0.45 s at full speed just before it would brake: the
    robot, and its commands, go past the leg's end and its margin. Coming back is no further
    off the leg (it failed: "stopped 0.08 m short of the goal ... odometry disagrees")."""
    robot = LoadedRobot([Stall("process", 2.59, 0.43)])
    start = robot.sim.get_state()
    result = go2_agent(robot).execute_mission("walk forward 1.11 meters")
    robot.sleep(2.0)
    assert result.success, result.response
    assert abs(robot.sim.get_state().x - start.x - 1.11) <= 0.05


def test_a_lie_larger_than_the_stalls_explain_is_still_caught_under_load() -> None:
    """Under load the check allows for the stalls it saw (here 0.3 s: about 14 degrees at the
    turn's speed); a heading jump of 25 degrees is more than that, and fails the turn."""
    robot = LoadedRobot([Stall("driver", 0.2, 0.3), Stall("process", 0.8, 0.3)])
    start = robot.sim.get_state()
    robot.lie(Faults(jump=(0.0, 0.0, math.radians(25.0)), after_deg=40.0))
    result = go2_agent(robot).execute_mission("turn left 90 degrees")
    robot.sleep(3.0)
    assert not result.success, (turned(robot, start.yaw), result.response)
    assert "odometry" in result.response and "The robot is stopped." in result.response
    assert turned(robot, start.yaw) < 90.0 - 5.0, turned(robot, start.yaw)


@pytest.mark.parametrize("jump", [-20.0, -60.0])
def test_a_lie_that_the_turn_lags_is_caught_when_no_stall_explains_it(jump: float) -> None:
    """A heading jump back (odometry shows the turn short, the commands would turn on) with
    the driver stalled as the turn began and again later: only what a stall could have held up
    (here its first speed-ups) lets the commands go further. Allowing the longest stall for
    every speed-up let a 20 degree lie turn the robot to 110 degrees, reported as done."""
    stalls = [Stall("driver", 0.05, 0.45), Stall("driver", 0.6, 0.45)]
    robot = LoadedRobot(stalls)
    start = robot.sim.get_state()
    robot.truths.clear()
    robot.lie(Faults(jump=(0.0, 0.0, math.radians(jump)), after_deg=30.0))
    result = go2_agent(robot).execute_mission("turn left 90 degrees")
    robot.sleep(3.0)
    most = max(math.degrees(math.remainder(t.yaw - start.yaw, math.tau)) for t in robot.truths)
    assert not result.success, (most, result.response)
    assert most <= 90.0 + 5.0, (most, result.response)


# Who stalls in the property: a whole process, which odometry shows (a driver's command path
# stalling alone shows only in a late start: the tests above).
SEEN = tuple(who for who in WHO if who != "commands")


def stalls_of(seed: int, longest: float, apart: float) -> list[Stall]:
    """A minute of stalls of any process, each up to `longest` seconds, `apart` seconds apart
    on average and at least 0.2 s (back to back they are one longer stall: more than a step
    allows for, MAX_STALL)."""
    rng = random.Random(seed)
    out, t = [], rng.uniform(0.0, 1.0)
    while t < 60.0:
        seconds = rng.uniform(0.02, longest)
        out.append(Stall(rng.choice(SEEN), t, seconds))
        t += seconds + 0.2 + rng.expovariate(1.0 / apart)
    return out


@settings(max_examples=30, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    seed=st.integers(0, 100_000),
    longest=st.sampled_from([0.1, 0.3, 0.5]),
    apart=st.sampled_from([0.3, 1.0]),
    mission=st.sampled_from(["turn left", "turn right", "walk forward", "walk backward"]),
    amount=st.floats(0.0, 1.0),
)
def test_an_honest_robot_on_a_loaded_machine_succeeds_in_truth(
    seed: int, longest: float, apart: float, mission: str, amount: float
) -> None:
    """Any turn (30 to 180 degrees) or walk (0.3 to 2 m) while ShadowHound's control loop, its
    ROS thread and the driver each stall now and then (every `apart` seconds on average), up to
    `longest` seconds (seen on loaded 2-core machines): it succeeds, ends within the step's
    outcome tolerance in truth, and goes beyond the step's margin in truth by no more than the
    robot covers in the longest stall at its speed (a control loop that stalls as it should
    brake cannot brake sooner; on a Go2 the watchdog stops it after `watchdog_timeout`)."""
    stalls = stalls_of(seed, longest, apart)
    robot = LoadedRobot(stalls)
    agent = go2_agent(robot)
    lim, m = agent.settings.safety, agent.settings.motion
    turning = mission.startswith("turn")
    size = round(30 + 150 * amount) if turning else round(0.3 + 1.7 * amount, 2)
    start = robot.sim.get_state()
    robot.truths.clear()
    result = agent.execute_mission(f"{mission} {size} {'degrees' if turning else 'meters'}")
    robot.sleep(2.0)  # whatever the robot still does after the mission, the truth shows
    assert result.success, (longest, result.response)
    end = robot.sim.get_state()
    sign = -1.0 if mission.endswith(("right", "backward")) else 1.0
    stall = max(s.seconds for s in stalls)
    if turning:
        done = [math.degrees(t.yaw - start.yaw) * sign % 360.0 for t in robot.truths]
        last = math.degrees(end.yaw - start.yaw) * sign % 360.0
        assert abs(last - size) <= lim.outcome_tolerance_deg, (last, result.response)
        beyond = math.degrees(
            turn_margin(lim, math.radians(size)) + m.default_angular_speed * stall
        )
        assert max(t for t in done if t < 270.0) <= size + beyond, result.response
    else:
        ahead = [(t.x - start.x) * sign for t in robot.truths]
        off = math.hypot(end.x - start.x - sign * size, end.y - start.y)
        assert off <= lim.outcome_tolerance, (off, result.response)
        beyond = leg_margin(lim, size) + m.default_linear_speed * stall
        assert max(ahead) <= size + beyond, result.response
