"""The lanes recordings are read and transcribed on (issue 32): a short recording (a spoken
stop) is never stuck behind long ones, the newest goes first, the queue is bounded and a
request heard too late is not sent on. Jobs block on events; nothing here waits on time."""

from __future__ import annotations

import threading
from collections.abc import Callable
from concurrent.futures import Future

import pytest

from shadowhound.hearing import HearingBusy, Lanes
from tests.web.conftest import wait_for


class Jobs:
    """Jobs that say when they start and may wait for `gate`."""

    def __init__(self) -> None:
        self.started: list[str] = []
        self.gate = threading.Event()

    def job(self, name: str, block: bool = False) -> Callable[[], str]:
        def run() -> str:
            self.started.append(name)
            if block:
                self.gate.wait(30)
            return name

        return run


def refused(future: Future[str]) -> HearingBusy:
    with pytest.raises(HearingBusy) as why:
        future.result(timeout=30)
    return why.value


def test_a_short_recording_goes_at_once_while_long_ones_wait_then_the_newest_first() -> None:
    jobs = Jobs()
    lanes = Lanes("test", "the test", workers=1, reserved=1, max_waiting=8, max_wait=600)
    first = lanes.submit(jobs.job("long0", block=True), urgent=False)
    wait_for(lambda: jobs.started == ["long0"], 10, "the first long job to start")
    waiting = [lanes.submit(jobs.job(f"long{i}"), urgent=False) for i in (1, 2, 3)]
    stop = lanes.submit(jobs.job("stop"), urgent=True)
    assert stop.result(timeout=30) == "stop"  # on the reserved worker, the others still wait
    assert not first.done() and not any(f.done() for f in waiting)
    jobs.gate.set()
    assert [f.result(timeout=30) for f in waiting] == ["long1", "long2", "long3"]
    assert jobs.started == ["long0", "stop", "long3", "long2", "long1"]  # newest first
    lanes.close()


def test_a_full_queue_pushes_out_the_oldest_least_urgent_at_once() -> None:
    jobs = Jobs()
    lanes = Lanes("test", "the test", workers=1, reserved=0, max_waiting=2, max_wait=600)
    busy = lanes.submit(jobs.job("busy", block=True), urgent=False)
    wait_for(lambda: jobs.started == ["busy"], 10, "the worker to be busy")
    a = lanes.submit(jobs.job("a"), urgent=False)
    b = lanes.submit(jobs.job("b"), urgent=False)
    urgent = lanes.submit(jobs.job("urgent"), urgent=True)
    why = refused(a)  # answered while the worker is still busy: the queue is bounded
    assert why.status == 429 and "say it again" in str(why) and not busy.done()
    c = lanes.submit(jobs.job("c"), urgent=False)
    assert refused(b).status == 429  # the oldest non-urgent goes, not the urgent one
    assert not c.done() and not urgent.done()
    jobs.gate.set()
    assert urgent.result(timeout=30) == "urgent" and c.result(timeout=30) == "c"
    lanes.close()


def test_a_recording_that_waited_too_long_is_not_sent_on() -> None:
    now = [0.0]
    jobs = Jobs()
    lanes = Lanes(
        "test", "the test", workers=1, reserved=0, max_waiting=8, max_wait=5, clock=lambda: now[0]
    )
    lanes.submit(jobs.job("busy", block=True), urgent=False)
    wait_for(lambda: jobs.started == ["busy"], 10, "the worker to be busy")
    late = lanes.submit(jobs.job("late"), urgent=False)
    now[0] = 6.0
    jobs.gate.set()
    why = refused(late)
    assert why.status == 503 and "waited 6 s for the test" in str(why)
    assert "late" not in jobs.started
    lanes.close()


def test_closing_answers_what_waits_and_refuses_what_comes() -> None:
    jobs = Jobs()
    lanes = Lanes("test", "the test", workers=1, reserved=0, max_waiting=8, max_wait=600)
    lanes.submit(jobs.job("busy", block=True), urgent=False)
    wait_for(lambda: jobs.started == ["busy"], 10, "the worker to be busy")
    waiting = lanes.submit(jobs.job("waiting"), urgent=False)
    gone = lanes.submit(jobs.job("gone"), urgent=False)
    assert gone.cancel()  # its client went away: never run
    lanes.close()
    assert refused(waiting).status == 503
    assert refused(lanes.submit(jobs.job("after"), urgent=True)).status == 503
    jobs.gate.set()
    assert jobs.started == ["busy"]
