"""Live events for browsers: a thread-safe fan-out from the agent's threads to asyncio clients.

The agent emits events on the mission worker's thread (and on whatever thread pressed the
e-stop); each WebSocket or SSE client reads its own bounded asyncio queue in the server's event
loop. A slow client loses its oldest events rather than slowing the mission down.
"""

from __future__ import annotations

import asyncio
import json
import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from typing import Any

log = logging.getLogger(__name__)


class Subscription:
    """One client's view of the feed: `await next()` returns the next message (a dict)."""

    def __init__(self, feed: EventFeed, loop: asyncio.AbstractEventLoop, size: int) -> None:
        self._feed = feed
        self._loop = loop
        self._queue: asyncio.Queue[dict[str, Any]] = asyncio.Queue(size)
        self.dropped = 0

    def _put(self, message: dict[str, Any]) -> None:
        """Runs in the subscriber's loop (through call_soon_threadsafe)."""
        if self._queue.full():
            self._queue.get_nowait()  # the oldest is the least useful to a live display
            self.dropped += 1
        self._queue.put_nowait(message)

    def deliver(self, message: dict[str, Any]) -> bool:
        """Hand `message` over from any thread. False when the client's loop is gone."""
        try:
            self._loop.call_soon_threadsafe(self._put, message)
        except RuntimeError:  # the loop was closed: the client is gone
            return False
        return True

    async def next(self, timeout: float | None = None) -> dict[str, Any] | None:
        """The next message, or None after `timeout` seconds without one."""
        try:
            return await asyncio.wait_for(self._queue.get(), timeout)
        except asyncio.TimeoutError:
            return None

    def close(self) -> None:
        self._feed.unsubscribe(self)


class EventFeed:
    """Numbered messages `{"seq", "kind", "time", ...}` to every subscriber.

    Recent messages (not the periodic `state` ticks) are kept so that a client that reconnects
    can ask for what it missed (SSE `Last-Event-ID`).
    """

    def __init__(self, backlog: int = 200, queue_size: int = 500,
                 scrub: Callable[[str], str] | None = None) -> None:
        self._lock = threading.Lock()
        self._seq = 0
        self._recent: deque[dict[str, Any]] = deque(maxlen=backlog)
        self._subscribers: list[Subscription] = []
        self._queue_size = queue_size
        self._scrub = scrub or (lambda text: text)

    @property
    def clients(self) -> int:
        with self._lock:
            return len(self._subscribers)

    def publish(self, kind: str, data: dict[str, Any], *, keep: bool = True) -> dict[str, Any]:
        """Send a message to every subscriber; returns it (with its sequence number)."""
        with self._lock:
            self._seq += 1
            message = {"seq": self._seq, "kind": kind, "time": time.time(), **data}
            if keep:
                self._recent.append(message)
            subscribers = list(self._subscribers)
        gone = [s for s in subscribers if not s.deliver(message)]
        for subscription in gone:
            self.unsubscribe(subscription)
        return message

    def subscribe(self, loop: asyncio.AbstractEventLoop, since: int | None = None
                  ) -> tuple[Subscription, list[dict[str, Any]]]:
        """A new subscription, and the kept messages after sequence number `since`."""
        subscription = Subscription(self, loop, self._queue_size)
        with self._lock:
            self._subscribers.append(subscription)
            missed = [] if since is None else [m for m in self._recent if m["seq"] > since]
        return subscription, missed

    def unsubscribe(self, subscription: Subscription) -> None:
        with self._lock:
            if subscription in self._subscribers:
                self._subscribers.remove(subscription)

    def encode(self, message: dict[str, Any]) -> str:
        """JSON text of a message with any secret value masked."""
        return self._scrub(json.dumps(message, default=str, separators=(",", ":")))
