"""Live events for browsers: a thread-safe fan-out from the agent's threads to asyncio clients.

Publishing costs the server once per event, whatever the number of clients: the message is
numbered, serialized and scrubbed once, appended to one shared ring, and each event loop with
clients gets at most one wake-up (coalesced). Each client reads the ring from its own cursor;
its bounded queue is the window between its cursor and the newest message. A client that falls
further behind than that window is never waited on: it is told (a `lagged` message, after which
its stream ends so it reconnects and reads the state) and the others go on. A client that keeps
up gets every message, in order.

Waking clients happens in slices of `WAKE_SLICE` per event-loop turn, so whatever else the loop
has to do (an e-stop request, a status poll) waits for at most one slice, not for every client.
Each loop has one sweep over its clients at a time: what is published during a sweep makes the
sweep go round once more when it ends (waking only clients with something to read), rather than
start a second sweep beside it, so bursts of events never add up to more than one slice a turn.
A client reads at most `limit` messages per wake-up and then waits for the next sweep (a client
still behind asks for one), so a backlog is sent a slice at a time too, not all at once.
"""

from __future__ import annotations

import asyncio
import logging
import threading
import time
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from .. import jsonout

log = logging.getLogger(__name__)

WAKE_SLICE = 8  # clients woken per event-loop turn
BATCH = 64  # messages handed to one client per read (bounds one client's turn in the loop)
LAGGED = "lagged"


@dataclass(frozen=True)
class Packet:
    """One message ready to send: its number (None for private messages), kind and JSON text."""

    seq: int | None
    kind: str
    text: str


class Subscription:
    """One client's view of the feed: `await next()` returns the next messages, in order.

    After a `lagged` packet the client is behind for good: send it and end the stream.
    """

    def __init__(self, feed: EventFeed, hub: _Hub, cursor: int) -> None:
        self._feed = feed
        self._hub = hub
        self.loop = hub.loop
        self.cursor = cursor  # the sequence number of the next message this client gets
        self.lagged = False
        self.closed = False
        self._private: deque[Packet] = deque(maxlen=16)  # e.g. WebSocket pongs
        self._waiter: asyncio.Future[None] | None = None
        self._started = False

    def deliver(self, message: dict[str, Any]) -> None:
        """Queue a message for this client only (from the client's own loop)."""
        self._private.append(Packet(None, str(message.get("kind", "")), self._feed.encode(message)))
        self.wake()

    def wake(self) -> bool:
        """Runs in the client's loop. True when the client was waiting (and now runs)."""
        waiter = self._waiter
        if waiter is not None and not waiter.done():
            waiter.set_result(None)
            return True
        return False

    def has_news(self) -> bool:
        """Something is waiting for this client (a published message or a private one)."""
        return bool(self._private) or self.cursor <= self._feed.last_seq

    async def next(self, timeout: float | None = None, limit: int = BATCH) -> list[Packet]:
        """The messages after the last ones returned (at most `limit`); [] after `timeout`
        seconds without any, or once closed. A last packet of kind `lagged` ends the
        subscription.

        The first call returns what is there; every later one waits to be woken (by the loop's
        sweep, a private message, the timeout or close), so a client never runs more than once
        per sweep, however far behind it is."""
        if not self._started:
            self._started = True
            packets = self._take(limit)
            if packets or self.lagged:
                return packets
        if self.closed or self.lagged:
            return []
        if self.has_news():  # still behind: a sweep comes for it
            self._feed.sweep_soon(self._hub)
        waiter: asyncio.Future[None] = self.loop.create_future()
        self._waiter = waiter
        timer = None if timeout is None else self.loop.call_later(timeout, self.wake)
        try:
            await waiter
        finally:
            self._waiter = None
            if timer is not None:
                timer.cancel()
        return [] if self.closed else self._take(limit)

    def _take(self, limit: int) -> list[Packet]:
        if self.lagged:
            return []
        packets = list(self._private)
        self._private.clear()
        found, missed = self._feed.read(self.cursor, limit)
        if missed:
            self.lagged = True
            packets.append(self._feed.lag_notice(self.cursor, missed))
            return packets
        if found:
            self.cursor = found[-1].seq + 1  # type: ignore[operator]  # ring packets have a seq
        return packets + found

    def close(self) -> None:
        self.closed = True
        self._feed.unsubscribe(self)
        if not self.loop.is_closed():
            self.loop.call_soon_threadsafe(self.wake)


class _Hub:
    """The subscribers that live in one event loop, whether a wake-up is on its way, and the
    loop's one sweep over them."""

    def __init__(self, loop: asyncio.AbstractEventLoop) -> None:
        self.loop = loop
        self.subscribers: list[Subscription] = []
        self.wake_pending = False  # under the feed's lock
        # In the loop's thread only: the clients this sweep has yet to wake (None: no sweep),
        # and whether something was published since the sweep began.
        self.sweep: deque[Subscription] | None = None
        self.again = False


class EventFeed:
    """Numbered messages `{"seq", "kind", "time", ...}` to every subscriber.

    `queue_size` is how far (in messages) a client may fall behind before it is dropped and
    told. Recent messages (not the periodic `state` ticks) are kept so that a client that
    reconnects can ask for what it missed (SSE `Last-Event-ID`).
    """

    def __init__(
        self, backlog: int = 200, queue_size: int = 500, scrub: Callable[[str], str] | None = None
    ) -> None:
        self._lock = threading.Lock()
        self._seq = 0
        self._ring: deque[Packet] = deque(maxlen=queue_size)
        self._recent: deque[Packet] = deque(maxlen=backlog)
        self._hubs: dict[asyncio.AbstractEventLoop, _Hub] = {}
        self._scrub = scrub or (lambda text: text)
        self.queue_size = queue_size

    @property
    def last_seq(self) -> int:
        """The number of the newest message (0 before any)."""
        return self._seq

    @property
    def clients(self) -> int:
        with self._lock:
            return sum(len(h.subscribers) for h in self._hubs.values())

    def publish(self, kind: str, data: dict[str, Any], *, keep: bool = True) -> dict[str, Any]:
        """Send a message to every subscriber (from any thread); returns it with its number."""
        wake = []
        with self._lock:  # numbering and the ring's order must agree
            self._seq += 1
            message = {"seq": self._seq, "kind": kind, "time": time.time(), **data}
            packet = Packet(self._seq, kind, self.encode(message))
            self._ring.append(packet)
            if keep:
                self._recent.append(packet)
            for hub in self._hubs.values():
                if hub.subscribers and not hub.wake_pending:
                    hub.wake_pending = True
                    wake.append(hub)
        for hub in wake:
            try:
                hub.loop.call_soon_threadsafe(self._wake, hub)
            except RuntimeError:  # that loop was closed: its clients are gone
                with self._lock:
                    self._hubs.pop(hub.loop, None)
        return message

    def subscribe(
        self, loop: asyncio.AbstractEventLoop, since: int | None = None
    ) -> tuple[Subscription, list[Packet]]:
        """A new subscription (from the next message on), and the kept messages after
        sequence number `since`."""
        with self._lock:
            hub = self._hubs.setdefault(loop, _Hub(loop))
            subscription = Subscription(self, hub, self._seq + 1)
            hub.subscribers.append(subscription)
            missed = (
                []
                if since is None
                else [p for p in self._recent if p.seq is not None and p.seq > since]
            )
        return subscription, missed

    def unsubscribe(self, subscription: Subscription) -> None:
        with self._lock:
            hub = self._hubs.get(subscription.loop)
            if hub is not None and subscription in hub.subscribers:
                hub.subscribers.remove(subscription)
                if not hub.subscribers:
                    self._hubs.pop(subscription.loop, None)

    def read(self, cursor: int, limit: int) -> tuple[list[Packet], int]:
        """(up to `limit` ring packets from sequence number `cursor` on, how many from `cursor`
        on are no longer in the ring)."""
        with self._lock:
            if not self._ring or cursor > self._seq:
                return [], 0
            first = self._ring[0].seq
            assert first is not None
            if cursor < first:
                return [], first - cursor
            start = cursor - first
            return [self._ring[i] for i in range(start, min(len(self._ring), start + limit))], 0

    def lag_notice(self, cursor: int, missed: int) -> Packet:
        message = {
            "seq": None,
            "kind": LAGGED,
            "time": time.time(),
            "next_seq": cursor,
            "missed": missed,
            "detail": f"this client fell more than {self.queue_size} events behind and "
            "is disconnected; reconnect (SSE: with Last-Event-ID to replay the "
            "kept events) and read GET /api/status",
        }
        return Packet(None, LAGGED, self.encode(message))

    def encode(self, message: dict[str, Any]) -> str:
        """Strict JSON text of a message (a number that is not finite is null: a browser's
        JSON.parse refuses NaN) with any secret value masked."""
        return self._scrub(jsonout.dumps(message, default=str, separators=(",", ":")))

    def _wake(self, hub: _Hub) -> None:
        """In the hub's loop: something was published; sweep over its waiting clients."""
        with self._lock:
            hub.wake_pending = False
        if hub.sweep is not None:  # a sweep is under way: it goes round again when it ends
            hub.again = True
            return
        self._start_sweep(hub)

    def sweep_soon(self, hub: _Hub) -> None:
        """In the hub's loop: a client is still behind; the sweep goes (round again) for it."""
        hub.again = True
        if hub.sweep is None:  # none under way: one starts next turn
            hub.sweep = deque()
            hub.loop.call_soon(self._end_sweep, hub)

    def _start_sweep(self, hub: _Hub) -> None:
        with self._lock:
            hub.sweep = deque(hub.subscribers)
        hub.again = False
        self._wake_slice(hub)

    def _wake_slice(self, hub: _Hub) -> None:
        """Wake up to WAKE_SLICE waiting clients with something to read; the rest next turn."""
        sweep = hub.sweep
        assert sweep is not None
        woken = 0
        while sweep and woken < WAKE_SLICE:
            subscription = sweep.popleft()
            # A client that is not waiting reads the news itself when it next asks.
            if subscription.has_news() and subscription.wake():
                woken += 1
        # The next slice, or the end of the sweep, is for the next turn: a sweep begun by a
        # `_wake` later in this turn would wake a second slice in it.
        hub.loop.call_soon(self._wake_slice if sweep else self._end_sweep, hub)

    def _end_sweep(self, hub: _Hub) -> None:
        if hub.again:  # published during the sweep: some clients may have missed it
            self._start_sweep(hub)
        else:
            hub.sweep = None
