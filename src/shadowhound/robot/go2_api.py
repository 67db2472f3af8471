"""Unitree Go2 sport API ids (topic rt/api/sport/request), as used by go2_ros2_sdk.

Pure data: the simulator, the ROS adapter and the `body.sport` skill all read this table.
"""

from __future__ import annotations

from dataclasses import dataclass

SPORT_TOPIC = "rt/api/sport/request"

DAMP = 1001
BALANCE_STAND = 1002
STOP_MOVE = 1003
STAND_UP = 1004
STAND_DOWN = 1005
RECOVERY_STAND = 1006
EULER = 1007
MOVE = 1008
SIT = 1009
RISE_SIT = 1010


@dataclass(frozen=True)
class Trick:
    """A sport-mode trick performed in place."""

    name: str
    api_id: int
    description: str
    duration: float  # seconds the robot is busy (simulator estimate)
    risky: bool = False  # can hurt people or the robot: needs explicit approval


TRICKS: dict[str, Trick] = {
    t.name: t
    for t in (
        Trick("hello", 1016, "wave a front paw in greeting", 3.0),
        Trick("stretch", 1017, "stretch the body", 4.0),
        Trick("dance1", 1022, "dance routine 1", 8.0),
        Trick("dance2", 1023, "dance routine 2", 8.0),
        Trick("wiggle_hips", 1033, "wiggle the hips", 4.0),
        Trick("finger_heart", 1036, "make a heart with the front paws", 4.0),
        Trick("scrape", 1029, "scrape (bow) with the front legs", 4.0),
        Trick("content", 1020, "show contentment", 3.0),
        Trick("pose", 1028, "strike a pose", 3.0),
        Trick("wallow", 1021, "roll around on the ground", 6.0),
        Trick("moonwalk", 1305, "moonwalk in place", 5.0),
        Trick("cross_step", 1302, "cross-step in place", 4.0),
        Trick("onesided_step", 1303, "step on one side in place", 4.0),
        Trick("recovery_stand", 1006, "recover to standing after a fall", 3.0),
        Trick("front_flip", 1030, "front flip", 3.0, risky=True),
        Trick("front_jump", 1031, "jump forward", 2.0, risky=True),
        Trick("front_pounce", 1032, "pounce forward", 2.0, risky=True),
        Trick("left_flip", 1042, "flip to the left", 3.0, risky=True),
        Trick("right_flip", 1043, "flip to the right", 3.0, risky=True),
        Trick("backflip", 1044, "back flip", 3.0, risky=True),
        Trick("handstand", 1301, "handstand on the front legs", 5.0, risky=True),
        Trick("bound", 1304, "bounding gait in place", 4.0, risky=True),
    )
}
