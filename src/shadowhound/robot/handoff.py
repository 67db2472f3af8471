"""Work handed off a ROS executor: the callback only keeps the message; a thread of its own
reads it (pure Python).

An executor thread also serves odometry and the stops: a callback that reads a large message
(a map, an image, a detector's boxes: rclpy takes 12 ms to read 100 boxes, 0.14 s for 1,000,
more on a loaded machine: bench/RESULTS.md) puts every callback after it in its queue behind
it. With `Handoff` the callback stores the message (constant time) and the thread reads it. It
keeps the newest `depth` messages, oldest first: depth 1 for inputs where only the newest counts
(a map, an image, detections: one that arrives before the previous was read replaces it), more
for a stream read in order (TF, whose messages carry different frames). However fast messages
come, the thread reads one at a time, and what it could not keep up with is counted
(`replaced`). rclpy holds the interpreter while it reads a message, so the process's other
threads still wait for each read (its size bounds that: input_limits); with `share` below 1 the
thread also rests after each message, so reading takes at most that share of its time, and a
flood costs the process that much, no more.
"""

from __future__ import annotations

import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Generic, TypeVar

T = TypeVar("T")
log = logging.getLogger(__name__)


class Handoff(Generic[T]):
    """`offer(item)` from a callback; `take(item)` runs on the thread `name`, in order."""

    def __init__(
        self, take: Callable[[T], None], name: str, depth: int = 1, share: float = 1.0
    ) -> None:
        self._take = take
        self._rest = 1.0 / share - 1.0  # seconds of rest per second of reading
        self._lock = threading.Lock()
        self._items: deque[T] = deque(maxlen=depth)
        self._ready = threading.Event()
        self._closed = threading.Event()
        self.replaced = 0  # items dropped for newer ones before they were taken
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def offer(self, item: T) -> bool:
        """Keep `item` for the thread; True when the oldest kept was dropped for it."""
        with self._lock:
            full = len(self._items) == self._items.maxlen
            self.replaced += full
            self._items.append(item)
        self._ready.set()
        return full

    def close(self) -> None:
        """End the thread (a read under way finishes; a rest ends at once)."""
        self._closed.set()
        self._ready.set()
        self._thread.join(2.0)

    def _run(self) -> None:
        while not self._closed.is_set():
            self._ready.wait()
            if self._closed.is_set():
                return
            with self._lock:
                if not self._items:
                    self._ready.clear()
                    continue
                item = self._items.popleft()
            began = time.thread_time()
            try:
                self._take(item)
            except Exception:  # a bug in one message's reading must not end the intake
                log.exception("reading a message on %s failed", self._thread.name)
            if self._rest > 0:
                self._closed.wait((time.thread_time() - began) * self._rest)
