import math
import threading
import time

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound import Posture, RobotAgent, RobotAgentConfig, RobotError, SimRobot
from shadowhound.config import SimConfig
from shadowhound.robot.sim.scene import DEFAULT_WORLD, World
from shadowhound.robot.sim.sensors import penetration


def test_starts_standing_at_origin_with_full_battery(robot):
    st = robot.get_state()
    assert (st.x, st.y, st.yaw) == (0.0, 0.0, 0.0)
    assert st.posture is Posture.STANDING and st.battery == 100.0


def test_velocity_integrates_in_odom_frame(robot):
    robot.reset(yaw=math.pi / 2)  # facing +y
    robot.send_velocity(0.5, 0.0, 0.0)
    robot.sleep(3.0)
    st = robot.get_state()
    assert abs(st.x) < 1e-6
    # 0.5 s ramp at 1 m/s^2 covers 0.125 m, then 2.5 s at full speed.
    assert st.y == pytest.approx(0.125 + 1.25, abs=1e-3)
    assert st.distance_travelled == pytest.approx(st.y, abs=1e-6)


def test_acceleration_and_speed_limits(robot):
    robot.send_velocity(5.0, 0.0, 9.0)  # beyond the Go2's hardware limits
    robot.sleep(0.1)
    assert robot.get_state().vx == pytest.approx(0.1, abs=1e-9)  # 1 m/s^2 for 0.1 s
    robot.sleep(5.0)
    st = robot.get_state()
    assert st.vx == pytest.approx(1.0) and st.wz == pytest.approx(2.0)


def test_motion_ignored_while_sitting_and_recorded(robot):
    robot.set_posture(Posture.SITTING)
    robot.send_velocity(0.3, 0.0, 0.0)
    robot.sleep(2.0)
    assert robot.get_state().distance_travelled == 0.0
    last = robot.commands[-1]
    assert last.kind == "velocity" and not last.accepted and "sitting" in last.note
    assert not robot.received_motion


def test_posture_state_machine_goes_through_standing(robot):
    robot.set_posture(Posture.SITTING)
    t0 = robot.now()
    robot.set_posture(Posture.LYING)
    assert robot.get_state().posture is Posture.LYING
    assert robot.now() - t0 == pytest.approx(1.0 + 1.5, abs=0.02)  # sit->stand->lie


def test_tricks_need_standing_and_do_not_translate(robot):
    robot.perform("hello")
    assert robot.get_state().distance_travelled == 0.0
    robot.set_posture(Posture.SITTING)
    with pytest.raises(RobotError, match="stand up first"):
        robot.perform("hello")
    with pytest.raises(RobotError, match="unknown trick"):
        robot.perform("moonwalk-ish")


def test_battery_drains_with_time_and_distance():
    robot = SimRobot(SimConfig(collisions=False))  # ten metres straight on: a ghost
    robot.sleep(100.0)
    idle = 100.0 - robot.get_state().battery
    assert idle == pytest.approx(1.0, rel=1e-6)
    robot.send_velocity(1.0, 0, 0)
    robot.sleep(10.0)
    assert 100.0 - robot.get_state().battery > idle + 0.3


def test_emergency_stop_latches(robot):
    robot.send_velocity(0.5, 0, 0)
    robot.sleep(1.0)
    robot.emergency_stop()
    assert robot.get_state().vx == 0.0
    robot.send_velocity(0.5, 0, 0)
    robot.sleep(1.0)
    x = robot.get_state().x
    robot.sleep(1.0)
    assert robot.get_state().x == x
    robot.release_estop()
    robot.send_velocity(0.5, 0, 0)
    robot.sleep(1.0)
    assert robot.get_state().x > x


def test_rejects_non_finite_velocity(robot):
    with pytest.raises(RobotError, match="finite"):
        robot.send_velocity(float("nan"), 0, 0)
    assert robot.get_state().vx == 0.0


def test_real_time_scale_follows_wall_clock():
    """The simulated clock keeps up with the wall clock (the 0.3 s slept at least) and never
    runs ahead of it, whatever the machine's load makes of the sleep."""
    before = time.monotonic()
    robot = SimRobot(time_scale=1.0)
    robot.send_velocity(0.2, 0, 0)
    time.sleep(0.3)
    simulated = robot.now()
    wall = time.monotonic() - before
    assert 0.3 <= simulated <= wall
    assert robot.get_state().x > 0


def test_stop_from_another_thread_wakes_sleep():
    """A stop pressed while the controller sleeps ends the sleep: long before its end (a minute
    of the robot's time, far more than the press takes even on a loaded machine). The press is
    repeated until the sleep returns, as a stop pressed before the sleep began has nothing to
    wake."""
    robot = SimRobot(time_scale=1.0)
    woke = threading.Event()

    def press() -> None:
        while not woke.wait(0.01):
            robot.stop()

    presser = threading.Thread(target=press, daemon=True)
    presser.start()
    try:
        robot.sleep(60.0)
        slept = robot.now()
    finally:
        woke.set()
        presser.join(10)
    assert slept < 60.0
    assert robot.counters["stops"] >= 1


def test_camera_frame_shows_the_world(robot):
    frame = robot.get_camera_frame()
    assert frame.encoding == "png" and frame.data.startswith(b"\x89PNG")
    assert (frame.width, frame.height) == (160, 120)
    assert frame.sightings and frame.sightings[0].name == "red ball"


def test_command_log_is_bounded():
    robot = SimRobot(SimConfig(command_log_size=10))
    for _ in range(50):
        robot.send_velocity(0.1, 0, 0)
    assert len(robot.commands) == 10
    assert robot.counters["motion_commands"] == 50


def test_invalid_time_scale():
    with pytest.raises(ValueError, match="time_scale"):
        SimRobot(time_scale=float("inf"))


# -- the clock at tiny time scales (issue 12, item 9) -------------------------------------------


def test_a_controllers_work_between_ticks_takes_no_simulated_time():
    """At a time scale of 0.001 a millisecond of the controller's own work would be a whole
    simulated second: while it ticks, simulated time passes only in its sleeps."""
    robot = SimRobot(time_scale=0.001)
    robot.sleep(0.05)
    start = robot.now()
    for _ in range(20):
        time.sleep(0.002)  # the controller computing its next command
        robot.send_velocity(0.2, 0, 0)
        robot.sleep(0.05)
    assert robot.now() - start == pytest.approx(1.0)


def test_an_idle_robot_still_follows_the_wall_clock_after_the_controller_stops():
    robot = SimRobot(time_scale=0.01)
    robot.sleep(0.05)
    robot.send_velocity(0.2, 0, 0)
    time.sleep(0.3)  # nobody ticks for longer than the grace: the wall clock asks for 30 s
    assert robot.now() >= 10.0 and robot.get_state().x > 1.5  # (at most 10 s per catch-up)


@pytest.mark.parametrize("scale", [0.001, 0.0001])
def test_motion_at_a_tiny_time_scale_succeeds(scale):
    robot = SimRobot(time_scale=scale)
    agent = RobotAgent(RobotAgentConfig(robot=robot))
    result = agent.execute_mission("walk forward 1 meter then turn left 90 degrees")
    assert result.success, result.response
    state = robot.get_state()
    assert state.x == pytest.approx(1.0, abs=0.01) and state.yaw == pytest.approx(
        math.pi / 2, abs=0.01
    )
    agent.cleanup()


def test_a_stalled_robot_still_fails_as_stalled_at_a_tiny_time_scale():
    robot = SimRobot(time_scale=0.001)
    robot.emergency_stop()  # latched in the robot itself: it ignores every velocity command
    agent = RobotAgent(RobotAgentConfig(robot=robot))
    result = agent.execute_mission("walk forward 1 meter")
    assert not result.success and "no progress for 3.0 s with 1.00 m to go" in result.response
    assert 3.0 <= result.steps[0].robot_duration < 5.0  # measured on the robot's clock
    agent.cleanup()


def test_true_path_is_ground_truth_about_1_cm_apart_and_bounded():
    robot = SimRobot(SimConfig(true_path_size=50), time_scale=0.0)
    robot.send_velocity(0.5, 0.0, 0.0)
    robot.sleep(0.8)  # 0.5 s ramp to 0.5 m/s (0.125 m), then 0.3 s at 0.5 m/s (0.15 m)
    path = robot.true_path
    assert path[0] == (0.0, 0.0, 0.0) and path[-1][1:] == (robot.get_state().x, 0.0)
    gaps = [math.hypot(b[1] - a[1], b[2] - a[2]) for a, b in zip(path, path[1:], strict=False)]
    # A point is kept once the body is 1 cm from the last one: gaps are 1 cm plus at most one
    # 10 ms physics substep (at most 1 cm at the hardware's 1 m/s), and the body never strays
    # more than 1 cm from the last point kept.
    assert min(gaps[:-1]) > 0.01 - 1e-9 and max(gaps) < 0.02 and robot.true_path_complete
    assert robot.true_odometer == pytest.approx(0.275, abs=1e-6)
    robot.sleep(1.0)  # another 0.5 m: more points than the 50 kept
    assert len(robot.true_path) == 51 and not robot.true_path_complete
    robot.stop()
    robot.reset(1.0, 2.0)  # a teleport is not a walk: the path starts again, the odometer stays
    assert robot.true_path == [(robot.now(), 1.0, 2.0), (robot.now(), 1.0, 2.0)]
    assert robot.true_path_complete and robot.true_odometer == pytest.approx(0.775, abs=1e-6)


# -- collisions and the range scan (issue 15) ----------------------------------------------

_COLLIDING = SimConfig(collisions=True)


@settings(max_examples=30, deadline=None)
@given(
    start=st.tuples(st.floats(-5.5, 5.5), st.floats(-5.5, 5.5), st.floats(-3.1, 3.1)),
    commands=st.lists(
        st.tuples(
            st.floats(-1.5, 1.5), st.floats(-1.5, 1.5), st.floats(-2.5, 2.5), st.floats(0.1, 3.0)
        ),
        min_size=1,
        max_size=6,
    ),
)
def test_random_motion_never_makes_the_body_overlap_an_object_or_wall(start, commands):
    robot = SimRobot(_COLLIDING)
    x, y, yaw = start
    if penetration(DEFAULT_WORLD, x, y, 0.35)[0] > 0:
        return  # a start inside something is not a pose the robot can be in
    robot.reset(x, y, yaw)
    for vx, vy, wz, seconds in commands:
        robot.send_velocity(vx, vy, wz)
        robot.sleep(seconds)
    assert robot.true_path_complete
    for _t, px, py in robot.true_path:
        assert penetration(DEFAULT_WORLD, px, py, 0.35)[0] <= 1e-9, (px, py)


def test_walking_into_the_red_ball_stops_at_contact_and_names_it():
    # The map the robot was given predates the ball, so the governor lets the walk start.
    stale = World(objects=tuple(o for o in DEFAULT_WORLD.objects if o.name != "red ball"))
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(_COLLIDING, map_world=stale)))
    result = agent.execute_mission("walk forward 4 meters")
    assert not result.success
    assert "blocked by the red ball 0.35 m ahead" in result.response
    assert result.robot.x == pytest.approx(3.0 - 0.2 - 0.35, abs=0.01)
    assert result.robot.blocked_by == "the red ball 0.35 m ahead"


def test_the_scan_sees_the_red_ball_ahead_and_the_walls():
    robot = SimRobot()
    scan = robot.get_scan()
    assert scan is not None and len(scan.ranges) == 360
    assert scan.ranges[180] == pytest.approx(3.0 - 0.2)  # beam 180 looks straight ahead
    assert scan.ranges[0] == pytest.approx(6.0)  # straight behind: the wall at x = -6
    assert scan.pose == robot.get_state().pose


def test_the_wall_stops_the_body_and_is_named():
    robot = SimRobot(_COLLIDING)
    robot.reset(0.0, 5.0, math.pi / 2)
    robot.send_velocity(0.5, 0.0, 0.0)
    robot.sleep(3.0)
    state = robot.get_state()
    assert state.y == pytest.approx(6.0 - 0.35, abs=1e-6)
    assert state.blocked_by == "the wall 0.35 m ahead"
    # Turning in place against the wall is free (the body is a circle), and walking away
    # clears the contact.
    robot.send_velocity(0.0, 0.0, 1.0)
    robot.sleep(1.0)
    assert robot.get_state().yaw != pytest.approx(math.pi / 2)
    robot.send_velocity(0.0, 0.0, 0.0)
    robot.sleep(1.0)
    robot.reset(0.0, 5.65, math.pi / 2)
    robot.send_velocity(-0.5, 0.0, 0.0)
    robot.sleep(1.0)
    state = robot.get_state()
    assert state.y < 5.4 and state.blocked_by == ""


def test_a_body_put_inside_an_object_may_only_move_out_of_it():
    robot = SimRobot(_COLLIDING)
    robot.reset(2.8, 0.0, 0.0)  # overlapping the red ball (x = 3, r = 0.2) by 0.55 m
    robot.send_velocity(0.5, 0.0, 0.0)  # further in: refused
    robot.sleep(1.0)
    assert robot.get_state().x == pytest.approx(2.8)
    assert "the red ball" in robot.get_state().blocked_by
    robot.send_velocity(-0.5, 0.0, 0.0)  # out: allowed
    robot.sleep(2.0)
    assert robot.get_state().x < 2.45


def test_without_collisions_the_body_passes_through_as_before():
    robot = SimRobot(SimConfig(collisions=False))
    assert robot.belief() is None  # and the robot is told of no map
    robot.send_velocity(1.0, 0.0, 0.0)
    robot.sleep(5.0)
    assert robot.get_state().x > 3.5 and robot.get_state().blocked_by == ""


@pytest.mark.parametrize("scale", [0.0, 1.0])
def test_the_simulator_implements_the_whole_robot_protocol(scale):
    """The agent uses a robot only through the declared protocol: the simulator offers all of
    it, and its clock is real time exactly when it has a time scale."""
    from shadowhound.robot.base import Robot

    robot = SimRobot(time_scale=scale)
    assert isinstance(robot, Robot)
    assert robot.realtime is (scale > 0) and robot.time_scale == scale
    robot.emergency_stop()
    assert robot.last_state().estopped
    robot.release_estop()
    assert not robot.get_state().estopped and robot.belief() is not None
