"""Lanes for the slow work on recordings (reading them, having them transcribed): threads of
their own, never the event loop that answers the e-stop and never asyncio's shared pool.

A job is *urgent* when it is short (a recording of a few seconds, which a spoken stop is).
Waiting jobs are taken urgent first, and the newest first: words said to a robot are about
now, and a "STOP!" said after six long requests should not wait for them. Some workers are
reserved for urgent jobs, so a short recording starts at once even while every other worker
waits on a slow server. The queue is bounded: a job arriving when `max_waiting` wait pushes
out the oldest of the least urgent, which is answered at once (HearingBusy, 429: say it
again), so the newest recording always gets in; a job that waited `max_wait` seconds is not
started (503: a request heard that late is no longer what the person wants now).
"""

from __future__ import annotations

import threading
import time
from collections.abc import Callable
from concurrent.futures import Future
from dataclasses import dataclass, field
from typing import Any

from ..errors import HearingBusy


@dataclass
class _Job:
    work: Callable[[], Any]
    urgent: bool
    arrived: float
    future: Future[Any] = field(default_factory=Future)

    @property
    def rank(self) -> tuple[bool, float]:
        """Higher goes first: urgent, then newer."""
        return self.urgent, self.arrived


class Lanes:
    """`workers` threads for any job and `reserved` more for urgent ones only (see above)."""

    def __init__(
        self,
        name: str,
        what: str,
        *,
        workers: int,
        reserved: int,
        max_waiting: int,
        max_wait: float,
        clock: Callable[[], float] = time.monotonic,
    ) -> None:
        """`name` names the threads; `what` is the work in words, for the answers ("the
        transcription server")."""
        self.what = what
        self.max_waiting, self.max_wait = max_waiting, max_wait
        self._clock = clock
        self._waiting: list[_Job] = []  # at most max_waiting + 1: scanned, not sorted
        self._changed = threading.Condition()
        self._closed = self._started = False
        self.running = 0
        # Started at the first job: an app that never hears anything keeps no threads.
        self._threads = [
            threading.Thread(
                target=self._work, args=(i >= workers,), name=f"shadowhound-{name}-{i}", daemon=True
            )
            for i in range(workers + reserved)
        ]

    @property
    def waiting(self) -> int:
        with self._changed:
            return len(self._waiting)

    def submit(self, work: Callable[[], Any], *, urgent: bool) -> Future[Any]:
        """`work()` on a lane; its future has the result, or HearingBusy when it never ran."""
        job = _Job(work, urgent, self._clock())
        with self._changed:
            if self._closed:
                _refuse(job, HearingBusy("the server is shutting down", 503))
                return job.future
            if not self._started:
                self._started = True
                for thread in self._threads:
                    thread.start()
            self._waiting.append(job)
            if len(self._waiting) > self.max_waiting:
                out = min(self._waiting, key=lambda j: j.rank)
                self._waiting.remove(out)
                _refuse(
                    out,
                    HearingBusy(
                        f"{self.max_waiting} newer recordings came while this one waited for "
                        f"{self.what}, and it was dropped to let them in: say it again",
                        429,
                    ),
                )
            self._changed.notify_all()
        return job.future

    def close(self) -> None:
        """Start nothing more: waiting jobs are answered 503; running ones finish."""
        with self._changed:
            self._closed = True
            for job in self._waiting:
                _refuse(job, HearingBusy("the server is shutting down", 503))
            self._waiting.clear()
            self._changed.notify_all()

    def _take(self, urgent_only: bool) -> _Job | None:
        """The next job this worker may run (under the lock), or None."""
        mine = [j for j in self._waiting if j.urgent or not urgent_only]
        if not mine:
            return None
        job = max(mine, key=lambda j: j.rank)
        self._waiting.remove(job)
        return job

    def _work(self, urgent_only: bool) -> None:
        while True:
            with self._changed:
                job = self._take(urgent_only)
                while job is None:
                    if self._closed:
                        return
                    self._changed.wait()
                    job = self._take(urgent_only)
                self.running += 1
            try:
                self._run(job)
            finally:
                with self._changed:
                    self.running -= 1

    def _run(self, job: _Job) -> None:
        waited = self._clock() - job.arrived
        if waited > self.max_wait:
            _refuse(
                job,
                HearingBusy(
                    f"this recording waited {waited:.0f} s for {self.what}, which was busy, and "
                    "was not sent on (a request heard that late is stale): say it again",
                    503,
                ),
            )
            return
        if not job.future.set_running_or_notify_cancel():
            return  # its client went away
        try:
            result = job.work()
        except BaseException as exc:  # noqa: BLE001 - handed to the waiting request as it is
            job.future.set_exception(exc)
        else:
            job.future.set_result(result)


def _refuse(job: _Job, why: HearingBusy) -> None:
    if job.future.set_running_or_notify_cancel():  # False: its client went away already
        job.future.set_exception(why)
