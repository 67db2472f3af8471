"""The teleop limiter (issue 27): whatever the stick and wherever the robot, what it commands
keeps to the speed caps and can always brake before the geofence (with the body's margin) and
before anything on the map. The pad end to end, judged by the simulator's truth, is in
tests/web/test_teleop_api.py and tests/web/test_browser_teleop.py."""

from __future__ import annotations

import math
from dataclasses import dataclass, field

from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound.config import ShadowHoundConfig
from shadowhound.robot.sim.robot import SimRobot
from shadowhound.skills.bounds import room_ahead
from shadowhound.state import RobotState
from shadowhound.teleop import MARGIN, Command, Teleop
from shadowhound.world import check_leg


class PlacedRobot(SimRobot):
    """The simulator's room and map, the robot reported at a chosen pose."""

    placed = RobotState()

    def last_state(self) -> RobotState:
        return self.placed


@dataclass
class Stand:
    """What Teleop reads of its agent: the robot, the settings, the e-stop."""

    robot: PlacedRobot
    settings: ShadowHoundConfig = field(default_factory=ShadowHoundConfig)
    estop_latched: bool = False


ROBOT = PlacedRobot(time_scale=0)
STAND = Stand(ROBOT)
STAND.settings.safety.geofence_radius = 4.0
unit = st.floats(-1.0, 1.0)


@settings(max_examples=400, deadline=None)
@given(
    x=st.floats(-4.5, 4.5),
    y=st.floats(-4.5, 4.5),
    yaw=st.floats(-math.pi, math.pi),
    stick=st.tuples(unit, unit, unit),
    before=st.tuples(st.floats(-0.5, 0.5), st.floats(-0.5, 0.5), st.floats(-1.0, 1.0)),
)
def test_whatever_the_stick_the_robot_can_brake_before_the_fence_and_the_map(
    x: float,
    y: float,
    yaw: float,
    stick: tuple[float, float, float],
    before: tuple[float, float, float],
) -> None:
    lim = STAND.settings.safety
    period = 1.0 / STAND.settings.motion.control_rate_hz
    ROBOT.placed = RobotState(x=x, y=y, yaw=yaw)
    teleop = Teleop(STAND)  # type: ignore[arg-type]
    teleop._sent = Command(*before)  # noqa: SLF001 (what it sent the tick before)
    command = teleop._limit(stick, period)  # noqa: SLF001
    speed = math.hypot(command.vx, command.vy)
    assert speed <= lim.max_linear_speed + 1e-9
    assert abs(command.wz) <= lim.max_angular_speed + 1e-9
    # Speeding up ramps at the acceleration caps; slowing down is at once.
    assert speed <= max(math.hypot(*before[:2]), 0) + lim.max_linear_accel * period + 1e-9
    if speed < 1e-9:
        return
    heading = yaw + math.atan2(command.vy, command.vx)
    braking = speed * speed / (2 * lim.max_linear_accel) + speed * period
    fence, _ = room_ahead(lim, ROBOT.placed.pose, heading, braking + 1.0)
    assert braking <= fence - MARGIN + 1e-6, (braking, fence)
    end = (x + (braking + 1e-3) * math.cos(heading), y + (braking + 1e-3) * math.sin(heading))
    belief = ROBOT.belief()
    assert belief is not None
    if belief.inflated.is_blocked(belief.grid.cell_of(x, y)):
        return  # it starts within an obstacle's clearance: check_leg's rule for leaving it holds
    leg = check_leg(belief, (x, y), end)
    assert leg.clear or leg.distance >= braking - 0.03, (leg, braking)  # a half cell's step


def test_off_it_takes_nothing_and_on_it_refuses_a_robot_that_is_not_standing() -> None:
    from shadowhound.state import Posture

    teleop = Teleop(STAND)  # type: ignore[arg-type]
    try:
        teleop.drive(1.0, 0.0, 0.0)
    except RuntimeError as exc:
        assert "switch it on first" in str(exc)
    else:
        raise AssertionError("drove while off")
    sitting = Stand(PlacedRobot(time_scale=0))
    sitting.robot.set_posture(Posture.SITTING)
    assert "stand it up first" in (Teleop(sitting).start() or "")  # type: ignore[arg-type]
    latched = Stand(PlacedRobot(time_scale=0), estop_latched=True)
    assert "e-stop is latched" in (Teleop(latched).start() or "")  # type: ignore[arg-type]
