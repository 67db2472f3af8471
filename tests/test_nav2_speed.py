"""nav.goto's check on Nav2's speed (skills/navigate.py), without ROS: the robot's own speed,
whatever SLAM does to its map pose and however late odometry comes (issue 32, item 4: a
flapping map -> odom read as 0.78 m/s while the robot walked at 0.40); a Nav2 that drives too
fast is still caught. The DDS side is tests/ros/test_go2_stamps.py."""

from __future__ import annotations

from collections import deque
from types import SimpleNamespace

import pytest
from hypothesis import example, given, settings
from hypothesis import strategies as st

from shadowhound.errors import SkillError
from shadowhound.skills.navigate import _check_speed
from shadowhound.state import RobotState

LIMIT = 0.5
TICK = 0.1  # seconds between the walk's checks


class Walk:
    """A robot walking at `speed` in truth, seen through odometry `late` seconds late at each
    tick (odometer and its moving time lag alike) and a map pose moved by `flaps`."""

    def __init__(self, speed: float, flaps: list[float], late: list[float]) -> None:
        self.speed, self.flaps, self.late = speed, flaps, late
        self.tick = 0

    def now(self) -> float:
        return self.tick * TICK

    def stalls(self, since: float) -> tuple:
        return ()  # the lateness is steady: no stall is seen

    def get_state(self) -> RobotState:
        shown = max(
            0.0, self.now() - self.late[self.tick % len(self.late)]
        )  # odometry's latest time
        flap = self.flaps[self.tick % len(self.flaps)]
        return RobotState(
            x=self.speed * shown + flap,  # the pose is odometry's, carried into the map
            y=-flap,
            distance_travelled=self.speed * shown,
            time_moving=shown,
        )


def run(walk: Walk, seconds: float = 4.0) -> None:
    ctx = SimpleNamespace(
        robot=walk, config=SimpleNamespace(safety=SimpleNamespace(max_linear_speed=LIMIT))
    )
    odometer: deque[tuple[float, float, float]] = deque()
    while walk.tick * TICK <= seconds:
        _check_speed(ctx, "Nav2", odometer)
        walk.tick += 1


flaps = st.lists(st.floats(-2.0, 2.0), min_size=1, max_size=20)


@settings(max_examples=60, deadline=None)
@given(st.floats(0.0, LIMIT), flaps)
def test_a_map_pose_that_flaps_is_no_speed(speed: float, offsets: list[float]) -> None:
    run(Walk(speed, offsets, [0.2]))


@settings(max_examples=60, deadline=None)
@given(st.floats(0.0, LIMIT), st.lists(st.floats(0.0, 0.5), min_size=1, max_size=20))
@example(LIMIT, [0.5] * 10 + [0.0] * 10)  # a second 0.5 s late, then a burst catches up
def test_odometry_that_comes_late_in_bursts_is_no_speed(speed: float, late: list[float]) -> None:
    """Each tick odometry is up to 0.5 s late, by a different amount: its count over a second
    may hold 1.5 s of steps, but its own moving time holds them too."""
    run(Walk(speed, [0.0], late))


@given(st.floats(0.7, 1.5), flaps)
def test_a_nav2_that_drives_too_fast_is_cancelled(speed: float, offsets: list[float]) -> None:
    with pytest.raises(SkillError, match=r"above the 0.5 m/s limit"):
        run(Walk(speed, offsets, [0.2]))
