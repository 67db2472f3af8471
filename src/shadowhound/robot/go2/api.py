"""Unitree Go2 sport API ids (topic rt/api/sport/request), as used by go2_ros2_sdk, and what
the robot reports back: sport modes, postures, body heights.

Pure data and two small rules of go2_ros2_sdk's: the simulated driver, the ROS robot, the
simulator and the `body.sport` skill all read these tables, so each fact lives here once.
Mode numbers are Unitree's SportModeState.mode; body heights and posture times are the
simulator's figures (firmware knowledge: check them on a robot).
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass
from enum import IntEnum
from types import MappingProxyType

from ...state import Posture

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

MOTION_SWITCHER_TOPIC = "rt/api/motion_switcher/request"
MOTION_SWITCH = 1002  # on MOTION_SWITCHER_TOPIC, parameter {"name": "ai"} or {"name": "normal"}


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

# Tricks the robot performs only on firmware that has them and after switching to the "ai"
# motion mode (MOTION_SWITCH with {"name": "ai"}); otherwise it ignores them.
AI_MODE_TRICKS = frozenset({1042, 1043, 1044, 1301, 1302, 1303, 1304, 1305})


def offered(ai_mode: bool) -> Mapping[str, Trick]:
    """The tricks a Go2 performs: all of them when it may switch to the "ai" motion mode
    (firmware that has them), else those that run in the normal mode."""
    if ai_mode:
        return MappingProxyType(TRICKS)
    return MappingProxyType({n: t for n, t in TRICKS.items() if t.api_id not in AI_MODE_TRICKS})


class SportMode(IntEnum):
    """`go2_states.mode`: the robot's sport mode (Unitree SportModeState.mode)."""

    IDLE = 0
    BALANCE_STAND = 1
    POSE = 2
    LOCOMOTION = 3
    LIE_DOWN = 5
    JOINT_LOCK = 6  # standing with locked joints (after StandUp): Moves are ignored
    DAMPING = 7
    RECOVERY_STAND = 8
    SIT = 10
    FRONT_FLIP = 11
    FRONT_JUMP = 12
    FRONT_POUNCE = 13


# The postures each mode can mean; the body height tells which, and when a change has ended.
# DAMPING is the limp robot lying (after Damp or a fall) and, on firmware that reports it after
# StandUp (a go2_webrtc_connect user's robot: unitree_webrtc_connect #17), the robot standing
# with its joints held. RECOVERY_STAND is a change under way, so it has none.
MODE_POSTURES: dict[int, frozenset[Posture]] = {
    SportMode.IDLE: frozenset({Posture.STANDING}),
    SportMode.BALANCE_STAND: frozenset({Posture.STANDING}),
    SportMode.POSE: frozenset({Posture.STANDING}),
    SportMode.LOCOMOTION: frozenset({Posture.STANDING}),
    SportMode.JOINT_LOCK: frozenset({Posture.STANDING}),
    SportMode.FRONT_FLIP: frozenset({Posture.STANDING}),
    SportMode.FRONT_JUMP: frozenset({Posture.STANDING}),
    SportMode.FRONT_POUNCE: frozenset({Posture.STANDING}),
    SportMode.LIE_DOWN: frozenset({Posture.LYING}),
    SportMode.DAMPING: frozenset({Posture.LYING, Posture.STANDING}),
    SportMode.SIT: frozenset({Posture.SITTING}),
}
# Modes in which the robot obeys Move (1008); in any other it ignores Moves.
WALKING_MODES = frozenset({SportMode.BALANCE_STAND, SportMode.LOCOMOTION})
# Body height (m) of each posture once reached; `go2_states.body_height` moves between them
# while a posture changes (the mode changes at once, so only the height tells the end).
BODY_HEIGHT: dict[Posture, float] = {
    Posture.STANDING: 0.32,
    Posture.SITTING: 0.20,
    Posture.LYING: 0.08,
}
BODY_HEIGHT_TOLERANCE = 0.02


def posture_of(mode: int, body_height: float) -> Posture | None:
    """The posture `go2_states` reports: the one of the mode's postures whose body height has
    been reached, else None (a posture change is under way, or the mode is not a posture)."""
    if not math.isfinite(body_height):
        return None
    for posture in MODE_POSTURES.get(mode, ()):
        if at_height(posture, body_height):
            return posture
    return None


def at_height(posture: Posture, body_height: float) -> bool:
    """`body_height` is the posture's, within BODY_HEIGHT_TOLERANCE."""
    return abs(body_height - BODY_HEIGHT[posture]) <= BODY_HEIGHT_TOLERANCE


@dataclass(frozen=True)
class PostureChange:
    """A sport command that changes posture. It takes time, ignores Moves meanwhile, and does
    not raise `progress`; the mode changes to `mode` when it starts, to `mode_after` at the end."""

    api_id: int
    name: str
    needs: frozenset[Posture]  # postures it starts from (others: the robot ignores it)
    target: Posture
    mode: SportMode
    mode_after: SportMode
    share: float  # fraction of the full posture time it takes (the simulator's estimate)


_ANY = frozenset(Posture)
_STANDING = frozenset({Posture.STANDING})
POSTURE_CHANGES: dict[int, PostureChange] = {
    c.api_id: c
    for c in (
        PostureChange(
            STAND_UP,
            "StandUp",
            _ANY,
            Posture.STANDING,
            SportMode.JOINT_LOCK,
            SportMode.JOINT_LOCK,
            1.0,
        ),
        PostureChange(
            BALANCE_STAND,
            "BalanceStand",
            _STANDING,
            Posture.STANDING,
            SportMode.BALANCE_STAND,
            SportMode.BALANCE_STAND,
            0.3,
        ),
        PostureChange(
            STAND_DOWN,
            "StandDown",
            _STANDING,
            Posture.LYING,
            SportMode.LIE_DOWN,
            SportMode.LIE_DOWN,
            1.0,
        ),
        PostureChange(SIT, "Sit", _STANDING, Posture.SITTING, SportMode.SIT, SportMode.SIT, 1.0),
        PostureChange(
            RISE_SIT,
            "RiseSit",
            frozenset({Posture.SITTING}),
            Posture.STANDING,
            SportMode.BALANCE_STAND,
            SportMode.BALANCE_STAND,
            1.0,
        ),
        PostureChange(
            RECOVERY_STAND,
            "RecoveryStand",
            _ANY,
            Posture.STANDING,
            SportMode.RECOVERY_STAND,
            SportMode.BALANCE_STAND,
            1.3,
        ),
        PostureChange(DAMP, "Damp", _ANY, Posture.LYING, SportMode.DAMPING, SportMode.DAMPING, 0.3),
    )
}


MOVE_QUANTUM = 0.01  # m/s and rad/s: go2_ros2_sdk rounds a Move to 2 decimals


def movable(v: float) -> float:
    """A velocity as a Move carries it: to 2 decimals, and a small one that would round to
    zero (the robot would stand still) at the smallest the robot obeys, with its sign."""
    if v == 0.0:
        return 0.0
    return math.copysign(max(MOVE_QUANTUM, round(abs(v), 2)), v)


def move_parameter(x: float, y: float, z: float) -> dict[str, float] | None:
    """What go2_ros2_sdk sends for a Twist (x, y forward/left m/s, z yaw rate rad/s): None for
    an all-zero Twist, which it drops (a zero Twist stops nothing), else the Move (1008)
    parameter, rounded to 2 decimals."""
    if x == 0.0 and y == 0.0 and z == 0.0:
        return None
    return {"x": round(x, 2), "y": round(y, 2), "z": round(z, 2)}
