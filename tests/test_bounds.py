"""The bounds a running step keeps from its own commands (skills/bounds.py, issue 21)."""

from __future__ import annotations

import math

from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound.config import SafetyConfig
from shadowhound.robot.base import Stall
from shadowhound.skills.bounds import (
    CommandLedger,
    Leeway,
    leg_room,
    room_ahead,
    turn_room,
)
from shadowhound.state import Pose2D


def to_segment(p: tuple[float, float], b: tuple[float, float]) -> float:
    n = b[0] ** 2 + b[1] ** 2
    t = 0.0 if n == 0 else max(0.0, min(1.0, (p[0] * b[0] + p[1] * b[1]) / n))
    return math.hypot(p[0] - t * b[0], p[1] - t * b[1])


_XY = st.floats(-3.0, 3.0)


@settings(max_examples=300, deadline=None)
@given(gx=_XY, gy=_XY, ax=_XY, ay=_XY, heading=st.floats(-math.pi, math.pi))
def test_the_room_along_a_leg_ends_on_the_edge_of_the_capsule(gx, gy, ax, ay, heading) -> None:
    """Going `leg_room` ahead keeps within the margin of the planned leg, and a little more
    would not (unless the room reaches past everything). From outside (a stall carried the
    commands past it) it only comes back: never ending further from the leg than it began."""
    margin = 0.1
    goal, at = (gx, gy), (ax, ay)
    room = leg_room(at, heading, goal, margin)
    d = (math.cos(heading), math.sin(heading))
    end = (ax + room * d[0], ay + room * d[1])
    if to_segment(at, goal) > margin:
        assert to_segment(end, goal) <= max(margin, to_segment(at, goal)) + 1e-6
        return
    assert to_segment(end, goal) <= margin + 1e-6
    beyond = (ax + (room + 0.01) * d[0], ay + (room + 0.01) * d[1])
    reach = math.hypot(*goal) + 2 * margin + math.hypot(*at)
    assert room >= reach - 1e-9 or to_segment(beyond, goal) > margin


def test_a_leg_leaves_room_ahead_to_its_end_and_little_behind_it() -> None:
    assert math.isclose(leg_room((0.0, 0.0), 0.0, (1.0, 0.0), 0.07), 1.07, abs_tol=1e-6)
    assert math.isclose(leg_room((0.0, 0.0), math.pi, (1.0, 0.0), 0.07), 0.07, abs_tol=1e-6)
    assert math.isclose(leg_room((0.5, 0.0), math.pi / 2, (1.0, 0.0), 0.07), 0.07, abs_tol=1e-6)
    # Past its end (a stalled control loop held a command too long): back, all the way along it.
    assert math.isclose(leg_room((1.2, 0.0), math.pi, (1.0, 0.0), 0.07), 1.27, abs_tol=1e-6)


def test_a_turn_leaves_room_to_its_end_and_its_margin_back() -> None:
    m = math.radians(5)
    assert math.isclose(turn_room(0.0, 1.0, math.pi / 2, m), math.pi / 2 + m)
    assert math.isclose(turn_room(math.pi / 2, 1.0, math.pi / 2, m), m)
    assert math.isclose(turn_room(0.0, -1.0, math.pi / 2, m), m)  # back: only the margin
    assert turn_room(math.pi, 1.0, math.pi / 2, m) == 0.0


def test_the_ledger_dead_reckons_commands() -> None:
    ledger = CommandLedger(Pose2D(1.0, 2.0, math.pi / 2), t=0.0)
    ledger.set(0.0, 0.5, 0.0, 0.0)
    walked = ledger.set(2.0, 0.0, 0.0, 0.0)
    assert math.isclose(walked, 1.0)
    assert math.isclose(ledger.pose.x, 1.0, abs_tol=1e-9) and math.isclose(ledger.pose.y, 3.0)
    ledger.begin_leg(2.0, Pose2D(0.0, 0.0, 0.0))
    ledger.set(2.0, 0.0, 0.0, 1.0)
    assert math.isclose(ledger.offset(3.0)[2], 1.0)


def test_the_room_before_a_fence_counts_the_body() -> None:
    lim = SafetyConfig(geofence_radius=2.0, geofence_margin=0.4)
    room, name = room_ahead(lim, Pose2D(0.0, 0.0, 0.0), 0.0, 5.0)
    assert math.isclose(room, 1.6, abs_tol=1e-6) and "2 m" in name
    room, _ = room_ahead(lim, Pose2D(1.7, 0.0, 0.0), 0.0, 5.0)  # within the margin already
    assert room < 1e-6
    room, _ = room_ahead(lim, Pose2D(1.7, 0.0, 0.0), math.pi, 5.0)  # walking back is free
    assert math.isclose(room, 3.4, abs_tol=1e-6)  # to as near the far side as it is now


def test_the_leeway_counts_only_changes_a_stall_seen_could_have_held_up() -> None:
    """Issue 32: a change of speed counts by how long a stall around it may have held it up
    (from up to 0.1 s before it: a StopMove waits for the driver's request loop), and the
    changes one stall held are then followed at the acceleration limit; none counts with no
    stall seen."""
    ledger = CommandLedger(Pose2D(0.0, 0.0, 0.0), t=0.0)
    ledger.set(0.0, 0.4, 0.0, 0.0)  # a speed-up before any stall: held by none
    ledger.set(1.0, 0.2, 0.0, 0.0)  # a slowing in a stall that ends at 1.3
    ledger.set(2.0, 0.0, 0.0, 0.0)  # the stop, 0.05 s before a stall that ends at 2.5
    ahead = (1.0, 0.0, 0.0)
    lw = ledger.leeway([Stall(0.9, 1.3), Stall(2.05, 2.5)], ahead, 1.0)
    assert math.isclose(lw.ahead, 0.2 * 0.3 + 0.2**2 / 2 + 0.2 * 0.5 + 0.2**2 / 2)
    assert lw.behind == 0.0 and lw.aside == 0.0
    assert ledger.leeway([], ahead, 1.0) == Leeway()
    assert ledger.leeway([Stall(3.0, 3.4)], ahead, 1.0) == Leeway()  # after it all


def test_the_commands_catch_up_only_as_far_as_the_robot_lags_within_the_leeway() -> None:
    lw = Leeway(behind=0.1)
    assert lw.catch_up(0.05, 0.07) == 0.05
    assert lw.catch_up(0.15, 0.07) == 0.1
    assert lw.catch_up(0.2, 0.07) == 0.0  # more than the stalls and the margin explain


def test_a_stop_sent_at_once_counts_the_braking() -> None:
    ledger = CommandLedger(Pose2D(0.0, 0.0, 0.0), t=0.0)
    ledger.set(0.0, 0.4, 0.0, 0.0)
    walked = ledger.halt(1.0, 1.0, 3.0)
    assert math.isclose(ledger.pose.x, 0.4 + 0.4**2 / 2)
    assert math.isclose(walked, 0.4 + 0.08)
