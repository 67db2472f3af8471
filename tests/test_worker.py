"""The mission worker owns stop and cancel, and tells its listeners by event (pure Python, on a
real SimRobot): `estop()` stops the robot before it drops the queue, from any thread, also while
a mission walks; `cancel(mission_id)` removes a waiting job or stops the running one; a listener
that raises is logged and never stops the worker or the other listeners."""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Iterator

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from shadowhound.worker import (
    CANCEL_DROP_REASON,
    ESTOP_DROP_REASON,
    MissionJob,
    MissionWorker,
)

WAIT = 60.0  # seconds: a bound on anything here, never the expected time
# 30 s of walking at real time: an e-stop pressed once it walks lands mid-walk on any machine.
WALK = "walk backward 3 meters at 0.1 m/s"


class RecordingSim(SimRobot):
    """A SimRobot that notes, at its hard stop, which waiting jobs were still waiting."""

    def __init__(self, settings: ShadowHoundConfig) -> None:
        super().__init__(settings.sim, time_scale=1.0)
        self.watched: list[MissionJob] = []
        self.log: list[str] = []

    def emergency_stop(self) -> None:
        super().emergency_stop()
        waiting = [j.command for j in self.watched if not j.done.is_set()]
        self.log.append(f"robot stopped; still waiting: {waiting}")


@pytest.fixture
def robot() -> RecordingSim:
    return RecordingSim(ShadowHoundConfig())


@pytest.fixture
def agent(robot: RecordingSim) -> Iterator[RobotAgent]:
    a = RobotAgent(RobotAgentConfig(robot=robot, settings=ShadowHoundConfig()))
    a.initialize()
    yield a
    a.release_estop()
    a.cleanup()


@pytest.fixture
def worker(agent: RobotAgent) -> Iterator[MissionWorker]:
    w = MissionWorker(agent)
    yield w
    w.stop()


def running(agent: RobotAgent, job: MissionJob) -> None:
    """Wait until `job` is the mission the agent executes."""
    deadline = time.monotonic() + WAIT
    while time.monotonic() < deadline:
        diagnostics = agent.get_diagnostics()
        if job.started and diagnostics["status"] == "executing":
            return
        time.sleep(0.01)
    raise AssertionError(f"{job.command!r} never started")


def test_estop_stops_the_robot_before_it_drops_the_queue(
    agent: RobotAgent, robot: RecordingSim, worker: MissionWorker
) -> None:
    walking = MissionJob(WALK)
    waiting = [MissionJob("turn left 90 degrees"), MissionJob("sit down")]
    robot.watched = waiting

    def finished(job: MissionJob) -> None:
        if job.dropped:
            robot.log.append(f"dropped {job.command}")

    worker.on("finished", finished)
    for job in (walking, *waiting):
        assert worker.submit(job) is None
    running(agent, walking)
    dropped = worker.estop()
    assert robot.log == [
        "robot stopped; still waiting: ['turn left 90 degrees', 'sit down']",
        "dropped turn left 90 degrees",
        "dropped sit down",
    ]
    assert dropped == waiting
    assert all(j.done.is_set() and j.result is None for j in waiting)
    assert {j.dropped for j in waiting} == {ESTOP_DROP_REASON}  # one reason, whoever pressed
    assert walking.done.wait(WAIT) and walking.result is not None
    assert walking.result.status.value == "stopped" and "e-stop" in (walking.result.error or "")
    assert agent.estop_latched and robot.get_state().distance_travelled < 3


def test_estop_from_many_threads_while_a_mission_walks_and_missions_arrive(
    agent: RobotAgent, robot: RecordingSim, worker: MissionWorker
) -> None:
    walking = MissionJob(WALK)
    assert worker.submit(walking) is None
    running(agent, walking)
    go = threading.Barrier(5)
    submitted: list[MissionJob] = []
    problems: list[BaseException] = []

    def press() -> None:
        try:
            go.wait(WAIT)
            worker.estop()
        except BaseException as exc:  # noqa: BLE001 - reported by the assertion below
            problems.append(exc)

    def submit() -> None:
        try:
            go.wait(WAIT)
            for i in range(5):
                job = MissionJob(f"turn left {10 + i} degrees")
                if worker.submit(job) is None:
                    submitted.append(job)
        except BaseException as exc:  # noqa: BLE001
            problems.append(exc)

    threads = [threading.Thread(target=press) for _ in range(4)]
    threads.append(threading.Thread(target=submit))
    for t in threads:
        t.start()
    for t in threads:
        t.join(WAIT)
    assert not problems and not any(t.is_alive() for t in threads)
    assert walking.done.wait(WAIT) and walking.result is not None
    assert walking.result.status.value == "stopped"
    for job in submitted:  # every job ends: dropped by an e-stop, or refused by its latch
        assert job.done.wait(WAIT), job.command
        if job.result is None:
            assert job.dropped == ESTOP_DROP_REASON
        else:
            assert not job.result.success and "e-stop" in job.result.response
    assert robot.get_state().distance_travelled < 3
    assert not worker.busy and worker.current is None
    agent.release_estop()  # the worker still works
    after = MissionJob("turn left 10 degrees")
    assert worker.submit(after) is None and after.done.wait(WAIT)
    assert after.result is not None and after.result.success


def test_cancel_removes_a_waiting_job_and_stops_the_running_one(
    agent: RobotAgent, worker: MissionWorker
) -> None:
    seen: list[str] = []
    worker.on("finished", lambda job: seen.append(job.command))
    first, second = MissionJob("wait 60 seconds"), MissionJob("turn left 90 degrees")
    assert worker.submit(first) is None and worker.submit(second) is None
    running(agent, first)
    assert worker.cancel(second.mission_id) == "removed"
    assert second.done.is_set() and second.result is None  # at once, not when its turn comes
    assert second.dropped == CANCEL_DROP_REASON and seen == ["turn left 90 degrees"]
    assert worker.current is first and not first.done.is_set()
    assert worker.cancel(first.mission_id) == "cancelled"
    assert first.done.wait(WAIT) and first.result is not None
    assert first.result.status.value == "stopped"
    assert worker.cancel(first.mission_id) == "unknown"  # finished: nothing left to cancel
    assert worker.cancel("no-such-mission") == "unknown"
    assert not worker.busy
    after = MissionJob("turn left 10 degrees")  # a cancel is not a latch
    assert worker.submit(after) is None and after.done.wait(WAIT)
    assert after.result is not None and after.result.success


def test_listeners_run_by_event_in_order_and_unsubscribe(worker: MissionWorker) -> None:
    calls: list[str] = []
    worker.on("started", lambda job: calls.append(f"started 1: {job.command}"))
    unsubscribe = worker.on("started", lambda job: calls.append("started 2"))
    worker.on("finished", lambda job: calls.append(f"finished: done={job.done.is_set()}"))
    job = MissionJob("turn left 10 degrees")
    assert worker.submit(job) is None and job.done.wait(WAIT)
    assert calls == ["started 1: turn left 10 degrees", "started 2", "finished: done=False"]
    calls.clear()
    unsubscribe()
    unsubscribe()  # twice is harmless
    again = MissionJob("turn right 10 degrees")
    assert worker.submit(again) is None and again.done.wait(WAIT)
    assert calls == ["started 1: turn right 10 degrees", "finished: done=False"]
    with pytest.raises(ValueError, match="no worker event 'begun'; known: started, finished"):
        worker.on("begun", lambda job: None)  # type: ignore[arg-type]


def test_a_listener_that_raises_is_logged_and_breaks_nothing(
    worker: MissionWorker, caplog: pytest.LogCaptureFixture
) -> None:
    calls: list[str] = []

    def broken(job: MissionJob) -> None:
        raise RuntimeError(f"listener bug on {job.command}")

    worker.on("started", broken)
    worker.on("started", lambda job: calls.append("started"))
    worker.on("finished", broken)
    worker.on("finished", lambda job: calls.append("finished"))
    with caplog.at_level(logging.ERROR, logger="shadowhound.worker"):
        job = MissionJob("turn left 10 degrees", on_done=broken)
        assert worker.submit(job) is None and job.done.wait(WAIT)
        after = MissionJob("turn right 10 degrees")
        assert worker.submit(after) is None and after.done.wait(WAIT)
    assert job.result is not None and job.result.success and job.dropped is None
    assert after.result is not None and after.result.success
    assert calls == ["started", "finished"] * 2
    failures = [r for r in caplog.records if r.exc_info and "listener bug" in str(r.exc_info[1])]
    assert len(failures) == 5  # started and finished of both jobs, and the first one's on_done
    assert "'started' listener failed for mission 'turn left 10 degrees'" in caplog.text
    assert not worker.busy


def test_a_stopped_worker_refuses_new_jobs(agent: RobotAgent) -> None:
    worker = MissionWorker(agent)
    worker.stop()
    assert worker.submit(MissionJob("sit down")) == "the mission worker has stopped"
    assert worker.start_now(MissionJob("sit down")) == "the mission worker has stopped"
    assert not worker.busy
