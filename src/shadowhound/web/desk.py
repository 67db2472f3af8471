"""The mission desk: missions from the web, run on the one mission worker, with their records.

Pure Python (no FastAPI): the routes call this, and it calls only the agent's public API and
`MissionWorker`. A web mission's id is chosen here, answered at once, and given to the agent, so
records, events and the agent's results all carry the same `mission_id`.
"""

from __future__ import annotations

import threading
import time
from collections import OrderedDict
from dataclasses import dataclass, field
from typing import Any

from ..admission import ESTOP_LATCHED
from ..agent import RobotAgent
from ..events import MissionEvent
from ..worker import MissionJob, MissionWorker
from .feed import EventFeed


@dataclass(eq=False)
class WebMission:
    """A mission submitted through the web, from queued to its result."""

    job: MissionJob
    submitted: float = field(default_factory=time.time)
    started: float | None = None
    finished: float | None = None

    @property
    def id(self) -> str:
        return self.job.mission_id

    @property
    def state(self) -> str:
        """queued | running | finished | dropped (never ran)."""
        if self.job.done.is_set():
            return "dropped" if self.job.result is None else "finished"
        return "running" if self.started is not None else "queued"

    def to_dict(self, full: bool = True) -> dict[str, Any]:
        job, result = self.job, self.job.result
        out: dict[str, Any] = {
            "mission_id": self.id,
            "command": job.command,
            "dry_run": job.dry_run,
            "source": "web",
            "state": self.state,
            "submitted_at": self.submitted,
            "started_at": self.started,
            "finished_at": self.finished,
            "status": result.status.value if result else self.state,
            "success": result.success if result else None,
            "response": result.response if result else job.dropped,
            "error": result.error if result else job.dropped,
        }
        if full:
            out["result"] = result.to_dict() if result else None
        return out


class MissionDesk:
    """Queues web missions on a `MissionWorker` and publishes every agent event to `feed`.

    With `worker=None` the desk makes its own worker. An interface that already has one (the
    ROS node) passes it in; either way the desk listens to the worker's `started` / `finished`
    jobs (another interface's jobs on a shared worker are ignored there).
    """

    def __init__(
        self,
        agent: RobotAgent,
        feed: EventFeed,
        *,
        worker: MissionWorker | None = None,
        max_queue: int = 8,
        keep: int = 200,
    ) -> None:
        self.agent = agent
        self.feed = feed
        self._keep = keep
        self._lock = threading.Lock()
        self._records: OrderedDict[str, WebMission] = OrderedDict()
        self._own_worker = worker is None
        self.worker = worker or MissionWorker(agent, max_queue=max_queue)
        self._unlisten = [
            self.worker.on("started", self._job_started),
            self.worker.on("finished", self._job_finished),
        ]
        self._unsubscribe = agent.add_listener(self._on_event)

    # -- missions --------------------------------------------------------------------------

    def submit(self, command: str, dry_run: bool = False) -> tuple[WebMission | None, str | None]:
        """Queue a mission. Returns (record, None), or (None, why it was refused)."""
        if self.agent.estop_latched and not dry_run:
            return None, ESTOP_LATCHED
        record = WebMission(MissionJob(command, source="web", dry_run=dry_run))
        with self._lock:
            self._records[record.id] = record
        refused = self.worker.submit(record.job)
        if refused:
            with self._lock:
                self._records.pop(record.id, None)
            return None, refused
        self._trim()
        self.feed.publish("mission_queued", record.to_dict(full=False))
        return record, None

    def get(self, mission_id: str) -> WebMission | None:
        with self._lock:
            return self._records.get(mission_id)

    def missions(self, limit: int = 50) -> list[dict[str, Any]]:
        """Newest first: web missions, then missions the agent ran for other interfaces."""
        with self._lock:
            records = list(self._records.values())
        known = {r.id for r in records}
        out = [r.to_dict(full=False) for r in reversed(records)]
        for result in reversed(self.agent.history):
            if result.mission_id not in known:  # e.g. a ROS topic mission on the same agent
                out.append(
                    {
                        "mission_id": result.mission_id,
                        "command": result.mission,
                        "dry_run": result.dry_run,
                        "source": "agent",
                        "state": "finished",
                        "status": result.status.value,
                        "success": result.success,
                        "response": result.response,
                        "error": result.error,
                    }
                )
        return out[:limit]

    def cancel(self, mission_id: str) -> tuple[WebMission | None, str]:
        """Cancel a queued or running mission: (record, cancelled|finished|not_found)."""
        record = self.get(mission_id)
        if record is None:
            return None, "not_found"
        if record.job.done.is_set():
            return record, "finished"
        self.worker.cancel(record.id)  # a queued one is dropped, a running one stopped
        return record, "cancelled"

    def estop(self) -> int:
        """Stop the robot at once, latch, and drop waiting missions. Returns how many."""
        return len(self.worker.estop())

    def running(self) -> WebMission | None:
        job = self.worker.current
        return None if job is None else self._record_of(job)

    def queued(self) -> int:
        with self._lock:
            return sum(1 for r in self._records.values() if r.state == "queued")

    def close(self) -> None:
        self._unsubscribe()
        if self._own_worker:
            self.worker.stop()  # the jobs it drops still finish their records
        else:  # a shared worker runs on without this desk
            for unlisten in self._unlisten:
                unlisten()

    # -- worker listeners (on the worker's thread, or the one that dropped the job) ----------

    def _job_started(self, job: MissionJob) -> None:
        record = self._record_of(job)
        if record is not None:
            record.started = time.time()

    def _job_finished(self, job: MissionJob) -> None:
        record = self._record_of(job)
        if record is not None:
            record.finished = time.time()
            self.feed.publish("mission_record", record.to_dict())

    # -- internals -------------------------------------------------------------------------

    def _record_of(self, job: MissionJob) -> WebMission | None:
        """The desk's record of `job`; None for another interface's job on a shared worker."""
        record = self.get(job.mission_id)
        return record if record is not None and record.job is job else None

    def _on_event(self, event: MissionEvent) -> None:
        """Runs on the emitting thread (the worker's, or the one that pressed the e-stop)."""
        self.feed.publish(
            event.kind,
            {**event.data, "mission_id": event.mission_id or None, "event_time": event.time},
        )  # the JSON edge

    def _trim(self) -> None:
        """Forget the oldest finished records beyond `keep` (persistent history comes later)."""
        with self._lock:
            while len(self._records) > self._keep:
                oldest = next(iter(self._records.values()))
                if not oldest.job.done.is_set():
                    break
                self._records.pop(oldest.id)
