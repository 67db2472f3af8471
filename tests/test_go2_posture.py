"""PostureWatch: a Go2's posture from go2_states, which may flap (issue 21).

Reports are handed in as the robot's callback would, at the driver's 10 Hz; time is real but
short (each test feeds a few tenths of a second of reports).
"""

from __future__ import annotations

import threading
import time

import pytest

from shadowhound.errors import RobotError
from shadowhound.robot.go2.api import BODY_HEIGHT, SportMode
from shadowhound.robot.go2.posture import SETTLE, PostureWatch
from shadowhound.state import Posture

STANDING = (int(SportMode.BALANCE_STAND), BODY_HEIGHT[Posture.STANDING])
SITTING = (int(SportMode.SIT), BODY_HEIGHT[Posture.SITTING])
DAMPING = (int(SportMode.DAMPING), BODY_HEIGHT[Posture.STANDING])


def watch() -> PostureWatch:
    return PostureWatch(lambda _doing: None, "go2_states", timeout=2.0, stale=1.0)


def feed(w: PostureWatch, *reports: tuple[int, float], period: float = 0.1) -> object:
    shown = None
    for mode, height in reports:
        shown = w.update(mode, height)
        time.sleep(period)
    return shown


def test_a_posture_counts_once_every_report_shows_it_for_the_settle_time() -> None:
    w = watch()
    assert w.update(*SITTING) is None  # one report is no posture yet
    assert feed(w, *[SITTING] * int(SETTLE / 0.1 + 2)) is Posture.SITTING


def test_a_flapping_report_is_not_a_posture() -> None:
    """go2_states flapping between sitting and standing never settles as sitting."""
    w = watch()
    feed(w, *[STANDING] * 4)
    assert feed(w, SITTING, STANDING, SITTING, STANDING, SITTING) is None
    assert w.fresh() is None


def test_reach_waits_for_the_posture_to_settle_not_the_first_report() -> None:
    w = watch()
    feed(w, *[STANDING] * 4)
    stop = threading.Event()

    def flapping_then_sitting() -> None:
        for report in [SITTING, STANDING] * 3 + [SITTING] * 20:
            if stop.is_set():
                return
            w.update(*report)
            time.sleep(0.05)

    feeder = threading.Thread(target=flapping_then_sitting)
    began = time.monotonic()
    feeder.start()
    try:
        w.reach(Posture.SITTING, "Sit (api id 1009)")
    finally:
        stop.set()
        feeder.join()
    assert time.monotonic() - began >= 6 * 0.05 + SETTLE  # after the flapping, and settled


def test_a_fall_shows_as_a_settled_fall_mode() -> None:
    w = watch()
    feed(w, *[STANDING] * 4)
    assert not w.fallen()
    feed(w, DAMPING)
    assert not w.fallen()  # one report is no fall
    feed(w, *[DAMPING] * 4)
    assert w.fallen()


def test_reach_fails_clearly_when_the_posture_never_comes() -> None:
    w = PostureWatch(lambda _doing: None, "/go2_states", timeout=0.3, stale=1.0)
    feed(w, *[STANDING] * 4, period=0.05)
    with pytest.raises(RobotError, match="did not reach sitting within 0 s: /go2_states shows"):
        w.reach(Posture.SITTING, "Sit (api id 1009)")


STANDING_DAMPED = (int(SportMode.DAMPING), BODY_HEIGHT[Posture.STANDING])
LYING_DAMPED = (int(SportMode.DAMPING), BODY_HEIGHT[Posture.LYING])


def test_damping_at_standing_height_reads_as_standing_that_does_not_walk() -> None:
    """Some firmware reports Damping (7) after StandUp (issue 23): the body height tells a
    robot standing with held joints (BalanceStand makes it walk) from one lying limp."""
    w = watch()
    assert feed(w, *[STANDING_DAMPED] * 4) is Posture.STANDING
    assert not w.balanced()
    assert w.stood_up("StandUp (api id 1004)", bound=0.0)
    assert feed(w, *[LYING_DAMPED] * 4) is Posture.LYING
    assert not w.stood_up("StandUp (api id 1004)", bound=0.0)


def rise(w: PostureWatch, mode: int, stop: threading.Event) -> None:
    """Reports of a StandUp in `mode`: the body height rising to standing, then staying there
    (reported every 50 ms) until `stop`: the wait is never left with only stale reports."""
    heights = iter((0.08, 0.14, 0.2, 0.26))
    while not stop.is_set():
        w.update(mode, next(heights, BODY_HEIGHT[Posture.STANDING]))
        stop.wait(0.05)


def test_standing_up_is_evident_from_the_body_height_whatever_the_mode() -> None:
    """After StandUp: standing counts once the body height shows it (settled), in any mode,
    one ShadowHound does not know included."""
    for mode in (int(SportMode.JOINT_LOCK), int(SportMode.DAMPING), 4):
        w, stop = watch(), threading.Event()
        feeder = threading.Thread(target=rise, args=(w, mode, stop))
        feeder.start()
        try:
            # A generous bound: the wait returns as soon as standing is evident (about 0.5 s
            # of reports), and a loaded machine must not make it time out first.
            assert w.stood_up("StandUp (api id 1004)", bound=10.0), mode
        finally:
            stop.set()
            feeder.join()


def test_the_wait_for_standing_up_is_bounded_and_does_not_fail() -> None:
    """go2_states not showing standing (late, or a body height of another firmware) delays
    BalanceStand by `bound` at most; then it goes anyway (the robot queues postures)."""
    w = watch()
    feed(w, *[LYING_DAMPED] * 4, period=0.05)
    began = time.monotonic()
    assert not w.stood_up("StandUp (api id 1004)", bound=0.3)
    assert time.monotonic() - began >= 0.3
