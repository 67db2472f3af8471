"""One mission at a time, off an interface's own threads: a worker thread with a small queue.

Every interface (the ROS node, the web app, the MCP server, the CLI) submits missions here and
stops and cancels through here: `estop()` stops the robot first, then drops the queued missions
(so nothing starts by surprise after the e-stop is released), with one reason for all of them;
`cancel(mission_id)` removes a queued mission or stops the running one. Queued missions are
bounded; `start_now` accepts a job only when the worker is idle (a second action goal is
rejected). Interfaces that want to know when a job starts or ends register listeners by event
(`worker.on("started", fn)`, `worker.on("finished", fn)`); a listener that raises is logged and
never stops the worker or the other listeners. Every accepted mission is in the history from
the moment it is accepted (`queued`), and one that ends without starting is recorded `not_run`
with the reason, so a crash loses none.
"""

from __future__ import annotations

import logging
import threading
import uuid
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Literal, get_args

from .agent import RobotAgent
from .events import MissionEvent, MissionStarted
from .plan import SkillCall
from .result import MissionResult, MissionStatus
from .teleop import Teleop

log = logging.getLogger(__name__)

ESTOP_DROP_REASON = "the e-stop was pressed before it started"  # why queued jobs were dropped
CANCEL_DROP_REASON = "cancelled before it started"
SHUTDOWN_DROP_REASON = "shutting down"

JobEvent = Literal["started", "finished"]  # what a worker listener can be registered for
JOB_EVENTS: tuple[str, ...] = get_args(JobEvent)
CancelOutcome = Literal["removed", "cancelled", "unknown"]  # was queued | was running | neither
JobListener = Callable[["MissionJob"], None]


@dataclass(eq=False)
class MissionJob:
    """A mission to run. `on_event` sees the agent's events while this job runs."""

    command: str
    source: str = "topic"  # topic | action | web | mcp | cli
    mission_id: str = field(default_factory=lambda: uuid.uuid4().hex[:12])  # the agent's id too
    dry_run: bool = False
    on_event: Callable[[MissionEvent], None] | None = None
    result: MissionResult | None = None
    dropped: str | None = None  # why it never ran
    started: bool = False  # the agent started it (a mission record of its own exists)
    done: threading.Event = field(default_factory=threading.Event)
    cancelled: threading.Event = field(default_factory=threading.Event)
    on_done: Callable[[MissionJob], None] | None = None  # after `done` is set
    calls: list[SkillCall] | None = None  # explicit skill calls to run instead of planning


TELEOP_BUSY = (
    "a person is driving the robot (teleop): switch driving off first (with nobody driving, it "
    "switches itself off after teleop.idle_timeout)"
)


class MissionWorker:
    """Runs `MissionJob`s on one thread. Listeners (see `on`) run on that thread too, except
    for jobs that `estop`, `cancel` or `drop_queued` end before they start: those are reported
    on the calling thread."""

    def __init__(self, agent: RobotAgent, *, max_queue: int = 8) -> None:
        self._agent = agent
        self._max_queue = max_queue
        self._lock = threading.Lock()
        self._wake = threading.Condition(self._lock)
        self._waiting: deque[MissionJob] = deque()
        self._pending = 0  # queued + running (+ one being reported as finished)
        self._current: MissionJob | None = None
        self._stopping = False
        self._listeners: dict[str, list[JobListener]] = {name: [] for name in JOB_EVENTS}
        self._unsubscribe = agent.add_listener(self._forward)
        self.teleop = Teleop(agent)  # a person driving: on only while no mission runs or waits
        self._thread = threading.Thread(target=self._run, name="shadowhound-mission", daemon=True)
        self._thread.start()

    # -- listeners ---------------------------------------------------------------------------

    def on(self, event: JobEvent, listener: JobListener) -> Callable[[], None]:
        """Call `listener(job)` when a job starts (`"started"`: before the agent plans it) or
        ends (`"finished"`: its result, or why it never ran, is set; before `job.done`).
        Listeners run in the order registered. Returns a function that unsubscribes."""
        if event not in self._listeners:
            raise ValueError(f"no worker event {event!r}; known: {', '.join(JOB_EVENTS)}")
        with self._lock:
            self._listeners[event].append(listener)

        def unsubscribe() -> None:
            with self._lock:
                if listener in self._listeners[event]:
                    self._listeners[event].remove(listener)

        return unsubscribe

    def _notify(self, event: JobEvent, job: MissionJob) -> None:
        with self._lock:
            listeners = list(self._listeners[event])
        for listener in listeners:
            try:
                listener(job)
            except Exception:  # one interface's bug must not stop the others or the worker
                log.exception("a %r listener failed for mission %r", event, job.command[:80])

    # -- accepting ---------------------------------------------------------------------------

    @property
    def busy(self) -> bool:
        with self._lock:
            return self._pending > 0

    @property
    def current(self) -> MissionJob | None:
        return self._current

    def submit(self, job: MissionJob) -> str | None:
        """Queue a job. Returns None when accepted, else why it was refused."""
        return self._accept(job, idle_only=False)

    def start_now(self, job: MissionJob) -> str | None:
        """Accept a job only if nothing runs or waits. Returns None when accepted."""
        return self._accept(job, idle_only=True)

    def _accept(self, job: MissionJob, *, idle_only: bool) -> str | None:
        with self._lock:
            if self._stopping:
                return "the mission worker has stopped"
            if self.teleop.on:
                return TELEOP_BUSY
            if idle_only and self._pending:
                return "another mission is running; wait for it to finish or cancel it"
            if self._pending > self._max_queue:
                return (
                    f"{self._max_queue} missions are already waiting; wait for them or "
                    "cancel the running one"
                )
            self._pending += 1
        # Recorded before the worker can see it (its start then replaces the record).
        if not job.dry_run:  # dry runs move nothing and leave no record
            self._agent.memory.mission_queued(job.mission_id, job.command)
        with self._wake:
            self._waiting.append(job)
            self._wake.notify()
        return None

    # -- stopping ----------------------------------------------------------------------------

    def estop(self, reason: str = ESTOP_DROP_REASON) -> list[MissionJob]:
        """Emergency stop from any thread: the robot's hard stop first (latched, and the running
        mission is cancelled), then teleoperation ends and every waiting job is dropped with
        `reason`. Returns those."""
        self._agent.estop()  # first: the robot stops before any bookkeeping
        self.teleop.stop("the e-stop was pressed")
        return self.drop_queued(reason)

    def start_teleop(self) -> str | None:
        """Switch teleoperation on: None, or why not (a mission runs or waits, the e-stop is
        latched, the robot is not standing). No mission is taken while it is on."""
        with self._lock:
            if self._stopping:
                return "the mission worker has stopped"
            if self._pending and not self._agent.estop_latched:  # a latched e-stop says so first
                return (
                    "a mission is running or waiting: wait for it to finish or cancel it "
                    "before driving"
                )
            return self.teleop.start()

    def cancel(self, mission_id: str) -> CancelOutcome:
        """Cancel a job from any thread: a waiting one is removed (it finishes as not run), the
        running one is stopped within one control tick and ends `stopped`. Returns which."""
        with self._lock:
            job = next((j for j in self._waiting if j.mission_id == mission_id), None)
            if job is None:
                running = self._current
                if running is None or running.mission_id != mission_id:
                    return "unknown"
                running.cancelled.set()  # also covers a cancel before the agent starts it
                self._agent.cancel()  # under the lock: the next job cannot start meanwhile
                return "cancelled"
            self._waiting.remove(job)
        job.cancelled.set()
        job.dropped = CANCEL_DROP_REASON
        self._finish(job)
        return "removed"

    def drop_queued(self, reason: str) -> list[MissionJob]:
        """Remove every waiting job (not the running one); each finishes with `dropped`."""
        with self._lock:
            dropped = list(self._waiting)
            self._waiting.clear()
        for job in dropped:
            job.dropped = reason
            self._finish(job)
        return dropped

    def stop(self, timeout: float = 5.0) -> None:
        """Cancel the running mission, drop the queue and end the thread."""
        with self._wake:
            self._stopping = True  # from here on nothing is accepted
            self._wake.notify()
        self._agent.cancel()
        self.teleop.stop()
        self.drop_queued(SHUTDOWN_DROP_REASON)
        self._thread.join(timeout)
        self._unsubscribe()

    # -- the worker thread -------------------------------------------------------------------

    def _next(self) -> MissionJob | None:
        """The next job, now current; None once the worker stops."""
        with self._wake:
            while not self._waiting and not self._stopping:
                self._wake.wait()
            if self._stopping:
                return None
            self._current = self._waiting.popleft()
            return self._current

    def _run(self) -> None:
        while (job := self._next()) is not None:
            try:
                if job.cancelled.is_set():
                    job.dropped = CANCEL_DROP_REASON
                    continue
                self._notify("started", job)
                if job.calls is not None:  # the same checks as a planned step
                    job.result = self._agent.run_plan(
                        job.calls, job.command, mission_id=job.mission_id
                    )
                else:
                    run = self._agent.dry_run if job.dry_run else self._agent.execute_mission
                    job.result = run(job.command, mission_id=job.mission_id)
            except Exception as exc:  # the worker must survive anything a mission does
                log.exception("mission %r crashed", job.command[:80])
                self._crashed(job, exc)
            finally:
                self._current = None
                self._finish(job)

    def _crashed(self, job: MissionJob, exc: Exception) -> None:
        """A job whose mission raised: one that had started ends failed, with the reason, in
        its result and its record (never left `running`); one that had not is dropped."""
        reason = f"internal error: {exc!r}"
        if not job.started or job.dry_run:
            job.dropped = reason
            return
        self._agent.cancel()  # the robot stopped (the next mission clears the flag)
        job.result = MissionResult(
            mission_id=job.mission_id,
            mission=job.command,
            success=False,
            response=f"Failed: {reason}.",
            status=MissionStatus.FAILED,
            error=reason,
        )
        try:
            self._agent.memory.mission_ended(job.result.to_dict())
        except Exception:  # reporting must not stop the worker
            log.exception("recording the end of mission %r failed", job.command[:80])

    def _finish(self, job: MissionJob) -> None:
        try:
            if not job.dry_run and not job.started:
                reason = job.dropped or (job.result.response if job.result else "never started")
                self._agent.memory.mission_not_run(job.mission_id, job.command, reason)
        except Exception:  # reporting must not stop the worker
            log.exception("recording the end of mission %r failed", job.command[:80])
        self._notify("finished", job)
        with self._lock:
            self._pending -= 1
        job.done.set()
        if job.on_done is not None:
            try:
                job.on_done(job)
            except Exception:
                log.exception("the on_done of mission %r failed", job.command[:80])

    def _forward(self, event: MissionEvent) -> None:
        job = self._current
        if job is None or threading.current_thread() is not self._thread:
            return
        if isinstance(event, MissionStarted):
            job.started = True
            if job.cancelled.is_set():
                self._agent.cancel()  # a cancel that came before the agent cleared its flag
        if job.on_event is not None:
            job.on_event(event)
