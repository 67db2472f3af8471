"""One mission at a time, off an interface's own threads: a worker thread with a small queue.

Interfaces (the ROS node, the web app) submit missions here. Queued missions are bounded;
`start_now` accepts a job only when the worker is idle (a second action goal is rejected). The
e-stop drops queued missions so nothing starts by surprise after the e-stop is released.
Every accepted mission is in the history from the moment it is accepted (`queued`), and one
that ends without starting is recorded `not_run` with the reason, so a crash loses none.
"""

from __future__ import annotations

import logging
import queue
import threading
import uuid
from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Any

from .agent import RobotAgent
from .events import MissionEvent, MissionStarted
from .plan import SkillCall
from .result import MissionResult

log = logging.getLogger(__name__)

_STOP = object()
ESTOP_DROP_REASON = "the e-stop was pressed before it started"  # why queued jobs were dropped


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


class MissionWorker:
    """Runs `MissionJob`s on one thread. `on_start`/`on_finish` run on that thread too."""

    def __init__(
        self,
        agent: RobotAgent,
        *,
        on_start: Callable[[MissionJob], None],
        on_finish: Callable[[MissionJob], None],
        max_queue: int = 8,
    ) -> None:
        self._agent = agent
        self._on_start = on_start
        self._on_finish = on_finish
        self._queue: queue.Queue[Any] = queue.Queue()
        self._max_queue = max_queue
        self._lock = threading.Lock()
        self._pending = 0  # queued + running
        self._current: MissionJob | None = None
        self._unsubscribe = agent.add_listener(self._forward)
        self._thread = threading.Thread(target=self._run, name="shadowhound-mission", daemon=True)
        self._thread.start()

    @property
    def busy(self) -> bool:
        with self._lock:
            return self._pending > 0

    @property
    def current(self) -> MissionJob | None:
        return self._current

    def submit(self, job: MissionJob) -> str | None:
        """Queue a job. Returns None when accepted, else why it was refused."""
        with self._lock:
            if self._pending > self._max_queue:
                return (
                    f"{self._max_queue} missions are already waiting; wait for them or "
                    "cancel the running one"
                )
            self._pending += 1
        self._accepted(job)
        self._queue.put(job)
        return None

    def start_now(self, job: MissionJob) -> str | None:
        """Accept a job only if nothing runs or waits. Returns None when accepted."""
        with self._lock:
            if self._pending:
                return "another mission is running; wait for it to finish or cancel it"
            self._pending += 1
        self._accepted(job)
        self._queue.put(job)
        return None

    def _accepted(self, job: MissionJob) -> None:
        """Record the job before the worker can see it (its start then replaces the record)."""
        if not job.dry_run:  # dry runs move nothing and leave no record
            self._agent.memory.mission_queued(job.mission_id, job.command)

    def drop_queued(self, reason: str) -> list[MissionJob]:
        """Remove every waiting job (not the running one); each finishes with `dropped`."""
        dropped: list[MissionJob] = []
        while True:
            try:
                item = self._queue.get_nowait()
            except queue.Empty:
                break
            if item is _STOP:
                self._queue.put(item)
                break
            dropped.append(item)
        for job in dropped:
            job.dropped = reason
            self._finish(job)
        return dropped

    def stop(self, timeout: float = 5.0) -> None:
        """Cancel the running mission, drop the queue and end the thread."""
        self._agent.cancel()
        self.drop_queued("shutting down")
        self._queue.put(_STOP)
        self._thread.join(timeout)
        self._unsubscribe()

    def _run(self) -> None:
        while True:
            item = self._queue.get()
            if item is _STOP:
                return
            job: MissionJob = item
            self._current = job
            try:
                if job.cancelled.is_set():
                    job.dropped = "cancelled before it started"
                    continue
                self._on_start(job)
                if job.calls is not None:  # the same checks as a planned step
                    job.result = self._agent.run_plan(
                        job.calls, job.command, mission_id=job.mission_id
                    )
                else:
                    run = self._agent.dry_run if job.dry_run else self._agent.execute_mission
                    job.result = run(job.command, mission_id=job.mission_id)
            except Exception as exc:  # the worker must survive anything a mission does
                log.exception("mission %r crashed", job.command[:80])
                job.dropped = f"internal error: {exc!r}"
            finally:
                self._current = None
                self._finish(job)

    def _finish(self, job: MissionJob) -> None:
        try:
            if not job.dry_run and not job.started:
                reason = job.dropped or (job.result.response if job.result else "never started")
                self._agent.memory.mission_not_run(job.mission_id, job.command, reason)
            self._on_finish(job)
        except Exception:  # reporting must not stop the worker
            log.exception("reporting the end of mission %r failed", job.command[:80])
        finally:
            with self._lock:
                self._pending -= 1
            job.done.set()
            if job.on_done is not None:
                job.on_done(job)

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
