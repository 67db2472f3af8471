"""The Go2's sport-mode service as simulated for `shadowhound sim-driver` (no ROS), and the
go2_api rules both sides of the driver read (mode table, body heights, the Twist rule)."""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Iterator
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound.config import SimConfig
from shadowhound.robot.go2 import api as go2_api
from shadowhound.robot.go2.api import (
    BODY_HEIGHT,
    MODE_POSTURES,
    POSTURE_CHANGES,
    WALKING_MODES,
    SportMode,
    move_parameter,
    posture_of,
)
from shadowhound.robot.sim.robot import SimRobot
from shadowhound.sim_driver.sport import SimSportMode
from shadowhound.state import Posture

POSTURE_SECONDS = 0.2  # short, so the tests are quick; the behaviour does not depend on it
SAFETY = 60.0  # seconds: bounds a hung test (a loaded machine is slow), never what is asserted


class Outcome:
    """Collects the (accepted, note) a request reports, and waits for it. `look`, if given, is
    called as the report comes (on the robot's own thread, at the start of what it reports):
    what the test sees then is seen during a posture change, however late the test's own
    thread runs on a loaded machine."""

    def __init__(self, look: Callable[[], Any] | None = None) -> None:
        self.done = threading.Event()
        self.value: tuple[bool, str] | None = None
        self.look = look
        self.seen: Any = None

    def __call__(self, accepted: bool, note: str) -> None:
        self.value = (accepted, note)
        if self.look is not None:
            self.seen = self.look()
        self.done.set()

    def wait(self) -> tuple[bool, str]:
        assert self.done.wait(SAFETY), "the robot never acted on the request"
        assert self.value is not None
        return self.value


@pytest.fixture
def robot() -> Iterator[SimSportMode]:
    # A Move lasts a minute unless renewed: no test here races its lapse but the one about it.
    body = SimSportMode(
        SimRobot(SimConfig(time_scale=1.0)), move_timeout=SAFETY, posture_seconds=POSTURE_SECONDS
    )
    yield body
    body.close()


def request(
    body: SimSportMode, api_id: int, parameter: object = "", topic: str = go2_api.SPORT_TOPIC
) -> tuple[bool, str]:
    outcome = Outcome()
    body.request(api_id, parameter, topic, outcome)
    return outcome.wait()


def wait_idle(body: SimSportMode) -> None:
    for _ in range(int(SAFETY / 0.01)):
        truth = body.truth()
        if not truth.changing and not truth.trick:
            return
        body.sim.sleep(0.01)
    raise AssertionError("the posture change never ended")


@given(st.floats(-3, 3), st.floats(-3, 3), st.floats(-3, 3))
@settings(max_examples=200)
def test_a_twist_is_dropped_only_when_all_zero_and_otherwise_rounded(
    x: float, y: float, z: float
) -> None:
    move = move_parameter(x, y, z)
    if x == 0 and y == 0 and z == 0:
        assert move is None
    else:
        assert move == {"x": round(x, 2), "y": round(y, 2), "z": round(z, 2)}


def test_every_mode_of_a_posture_reads_back_as_that_posture_once_the_height_is_reached() -> None:
    for mode, postures in MODE_POSTURES.items():
        for posture in postures:
            assert posture_of(mode, BODY_HEIGHT[posture]) is posture
        others = [h for p, h in BODY_HEIGHT.items() if p not in postures]
        assert all(posture_of(mode, h) is None for h in others)  # still on its way
    # Damping: limp and lying, or (on some firmware, after StandUp) standing with held joints.
    assert MODE_POSTURES[SportMode.DAMPING] == {Posture.LYING, Posture.STANDING}
    assert posture_of(SportMode.RECOVERY_STAND, BODY_HEIGHT[Posture.STANDING]) is None
    assert posture_of(SportMode.SIT, math.nan) is None
    for change in POSTURE_CHANGES.values():  # every change ends in a mode of its posture
        assert change.target in MODE_POSTURES[change.mode_after]


def test_a_move_walks_and_stop_move_stops(robot: SimSportMode) -> None:
    assert robot.truth().mode == SportMode.BALANCE_STAND
    assert request(robot, go2_api.MOVE, {"x": 0.3, "y": 0.0, "z": 0.0}) == (True, "")
    while not robot.truth().moving:
        robot.sim.sleep(0.01)
    assert robot.truth().mode == SportMode.LOCOMOTION
    assert request(robot, go2_api.STOP_MOVE) == (True, "")
    while robot.truth().moving:
        robot.sim.sleep(0.01)
    truth = robot.truth()
    assert (truth.moves, truth.stop_moves, truth.moves_lapsed) == (1, 1, 0)
    assert truth.mode == SportMode.BALANCE_STAND


def test_a_move_lapses_unless_renewed() -> None:
    body = SimSportMode(SimRobot(SimConfig(time_scale=1.0)), move_timeout=0.3)
    try:
        assert body.move(0.2, 0.0, 0.0) == ""
        while body.truth().moves_lapsed == 0:
            assert body.truth().stop_moves == 0
            body.sim.sleep(0.01)
        while body.truth().moving:  # it brakes once the Move has run out
            body.sim.sleep(0.01)
        assert body.truth().moves == 1
    finally:
        body.close()


def test_postures_take_time_ignore_moves_and_leave_progress_at_zero(robot: SimSportMode) -> None:
    outcome = Outcome(lambda: (robot.truth(), robot.progress, robot.move(0.5, 0.0, 0.0)))
    robot.request(go2_api.STAND_DOWN, "", go2_api.SPORT_TOPIC, outcome)
    assert outcome.wait() == (True, "")
    during, progress, move = outcome.seen
    assert during.changing == "StandDown" and during.mode == SportMode.LIE_DOWN
    assert progress == 0
    assert move.startswith("ignored: StandDown is under way")
    wait_idle(robot)
    lying = robot.truth()
    assert lying.posture is Posture.LYING and lying.body_height == BODY_HEIGHT[Posture.LYING]
    assert posture_of(lying.mode, lying.body_height) is Posture.LYING
    assert (lying.x, lying.y, lying.moves, lying.moves_ignored) == (0.0, 0.0, 1, 1)
    assert robot.move(0.5, 0.0, 0.0).startswith("ignored: mode LIE_DOWN does not walk")
    assert request(robot, go2_api.SIT)[1].startswith("ignored: Sit needs the robot standing")
    # StandUp locks the joints: still no walking until BalanceStand.
    assert request(robot, go2_api.STAND_UP) == (True, "")
    wait_idle(robot)
    assert robot.truth().mode == SportMode.JOINT_LOCK
    assert robot.move(0.5, 0.0, 0.0).startswith("ignored: mode JOINT_LOCK does not walk")
    assert request(robot, go2_api.BALANCE_STAND) == (True, "")
    wait_idle(robot)
    assert robot.truth().mode == SportMode.BALANCE_STAND
    assert robot.move(0.5, 0.0, 0.0) == ""


def test_tricks_raise_progress_and_ai_mode_ones_need_the_motion_switch(robot: SimSportMode) -> None:
    handstand = go2_api.TRICKS["handstand"].api_id
    accepted, note = request(robot, handstand)
    assert not accepted and "'ai' motion mode" in note
    assert request(robot, go2_api.MOTION_SWITCH, {"name": "ai"}, go2_api.MOTION_SWITCHER_TOPIC) == (
        True,
        "",
    )
    assert robot.truth().ai_mode
    assert request(robot, go2_api.TRICKS["hello"].api_id) == (True, "")
    assert robot.progress == 1 and robot.truth().trick == "hello"


def test_bad_and_unknown_requests_are_ignored_with_a_reason(robot: SimSportMode) -> None:
    accepted, note = request(robot, go2_api.MOVE, {"x": 1})
    assert not accepted and "Move needs" in note
    assert request(robot, 4242) == (False, "not simulated: api id 4242")
    assert request(robot, go2_api.SIT, "", "rt/api/other")[0] is False
    assert robot.truth().posture is Posture.STANDING and not robot.truth().moving


def test_a_robot_can_start_lying_down() -> None:
    body = SimSportMode(SimRobot(SimConfig(time_scale=1.0)), start=Posture.LYING)
    try:
        truth = body.truth()
        assert (truth.posture, truth.mode) == (Posture.LYING, SportMode.LIE_DOWN)
        assert posture_of(truth.mode, truth.body_height) is Posture.LYING
        assert body.move(0.3, 0.0, 0.0).startswith("ignored: mode LIE_DOWN")
    finally:
        body.close()


def test_what_the_robot_reports_never_runs_ahead_of_its_posture(robot: SimSportMode) -> None:
    """While a posture changes, mode and body height never read as a posture the body is not
    in yet: a client that judges by them cannot finish early."""
    for api_id in (go2_api.SIT, go2_api.RISE_SIT, go2_api.STAND_DOWN, go2_api.STAND_UP):
        outcome = Outcome(robot.truth)  # the first sample, as the change starts
        robot.request(api_id, "", go2_api.SPORT_TOPIC, outcome)
        outcome.wait()
        samples = [outcome.seen]
        while True:
            truth = robot.truth()
            samples.append(truth)
            if not truth.changing:
                break
        assert len(samples) > 1
        for truth in samples:
            reported = posture_of(truth.mode, truth.body_height)
            assert reported is None or reported is truth.posture, truth


def test_go2_states_never_shows_a_walking_mode_while_moves_are_ignored(robot: SimSportMode) -> None:
    """A posture command ignores Moves while it runs, so the mode it leads to is shown only
    once it ends when that mode walks (BalanceStand from a locked stand moves no body height:
    the mode is the only sign of its end). A client that waits for a walking mode then never
    sends a Move the robot ignores (issue 23)."""
    steps = (go2_api.SIT, go2_api.RISE_SIT, go2_api.STAND_UP, go2_api.BALANCE_STAND)
    for api_id in steps:
        assert request(robot, api_id) == (True, ""), api_id
        while (truth := robot.truth()).changing:
            assert truth.mode not in WALKING_MODES, truth
        assert robot.truth().mode == POSTURE_CHANGES[api_id].mode_after
    assert robot.truth().mode == SportMode.BALANCE_STAND
    assert robot.move(0.3, 0.0, 0.0) == ""


def test_stand_up_may_report_another_mode_and_the_robot_walks_only_after_balance_stand() -> None:
    """`sim-driver --stand-up-mode 7`: a robot that reports Damping after StandUp (as one
    go2_webrtc_connect user's does) stands, at standing height, and ignores Moves until
    BalanceStand."""
    body = SimSportMode(
        SimRobot(SimConfig(time_scale=1.0)),
        posture_seconds=POSTURE_SECONDS,
        start=Posture.LYING,
        stand_up_mode=SportMode.DAMPING,
    )
    try:
        assert request(body, go2_api.STAND_UP) == (True, "")
        assert body.truth().mode == SportMode.DAMPING  # from the start of StandUp
        wait_idle(body)
        truth = body.truth()
        assert (truth.posture, truth.mode) == (Posture.STANDING, SportMode.DAMPING)
        assert posture_of(truth.mode, truth.body_height) is Posture.STANDING
        assert body.move(0.3, 0.0, 0.0).startswith("ignored: mode DAMPING does not walk")
        assert request(body, go2_api.BALANCE_STAND) == (True, "")
        wait_idle(body)
        assert body.truth().mode == SportMode.BALANCE_STAND
        assert body.move(0.3, 0.0, 0.0) == ""
    finally:
        body.close()
