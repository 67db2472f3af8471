"""Reading recordings in worker processes of their own.

Reading a length walks a container in Python (bounded: a few milliseconds for what a browser
sends, some tens for a crafted Ogg of 1,500 pages). In a thread of the server that work holds
the interpreter's lock, which the event loop needs to answer the e-stop, and on a busy machine a
thread preempted while holding it holds the loop for as long as the scheduler likes. In a
process of its own it holds nothing of the server's: the lane thread that waits for it has let
go of the lock. The processes start at the page's first look at push-to-talk (`warm`), not at
the first recording, which would otherwise wait for them, and serve every app of the server
process (`READERS`): they hold no state, and starting them costs a second or two.
"""

from __future__ import annotations

import multiprocessing
import threading
from concurrent.futures import ProcessPoolExecutor
from concurrent.futures.process import BrokenProcessPool

from ..errors import HearingBusy
from .audio import Audio, inspect

PROCESSES = 2  # one for each reading lane (the general and the urgent one)


def _ready() -> bool:
    return True


class Readers:
    """`PROCESSES` worker processes that read recordings (`inspect`), started on demand."""

    def __init__(self, processes: int = PROCESSES) -> None:
        self.processes = processes
        self._pool: ProcessPoolExecutor | None = None
        self._lock = threading.Lock()
        self._closed = False

    def warm(self) -> None:
        """Start the processes now (returns at once), so that no recording waits for them."""
        self._started()

    def inspect(self, data: bytes, content_type: str, max_seconds: float) -> Audio:
        """`hearing.inspect` in a worker process (the caller's thread waits, holding nothing)."""
        pool = self._started()
        if pool is None:
            raise HearingBusy("the server is shutting down", 503)
        try:
            return pool.submit(inspect, data, content_type, max_seconds).result()
        except BrokenProcessPool:
            with self._lock:  # a reader died (killed, out of memory): start new ones next time
                if self._pool is pool:
                    self._pool = None
            raise HearingBusy("the recording's reader stopped: say it again", 503) from None

    def close(self) -> None:
        with self._lock:
            self._closed = True
            pool, self._pool = self._pool, None
        if pool is not None:
            pool.shutdown(wait=False, cancel_futures=True)

    def _started(self) -> ProcessPoolExecutor | None:
        with self._lock:
            if self._closed:
                return None
            if self._pool is None:
                self._pool = ProcessPoolExecutor(
                    self.processes, mp_context=multiprocessing.get_context("spawn")
                )
                for _ in range(self.processes):  # each starts a process, in the background
                    self._pool.submit(_ready)
            return self._pool


READERS = Readers()  # the server process's readers, shared by its apps; they end with it
