"""The event fan-out (web/feed.py) on its own: ordering, bounded queues, lagging clients."""

from __future__ import annotations

import asyncio
import json
import threading

from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound.web.feed import LAGGED, WAKE_SLICE, EventFeed, Packet, Subscription


def _seqs(packets: list[Packet]) -> list[int]:
    return [p.seq for p in packets if p.seq is not None]


@settings(max_examples=40, deadline=None)
@given(bursts=st.lists(st.integers(1, 12), min_size=1, max_size=12), size=st.integers(4, 12))
def test_a_client_that_keeps_up_gets_every_event_in_order_and_a_slow_one_is_told(
    bursts: list[int], size: int
) -> None:
    """Whatever the bursts, a reader that is never more than `size` behind loses nothing; a
    reader that never reads gets a contiguous prefix, then `lagged`, then nothing more."""
    feed = EventFeed(queue_size=size)

    async def run() -> tuple[list[Packet], list[Packet], list[int]]:
        loop = asyncio.get_running_loop()
        fast, _ = feed.subscribe(loop)
        slow, _ = feed.subscribe(loop)
        got: list[Packet] = []
        published: list[int] = []
        for burst in bursts:
            for _ in range(min(burst, size)):  # keeping up: never more than `size` behind
                published.append(feed.publish("step", {"n": len(published)})["seq"])
            while not got or (_seqs(got) and _seqs(got)[-1] < published[-1]):
                got += await fast.next(timeout=60)
        slow_got: list[Packet] = []
        while not slow.lagged:
            batch = await slow.next(timeout=0.01)
            if not batch:
                break
            slow_got += batch
        return got, slow_got, published

    got, slow_got, published = asyncio.run(run())
    assert _seqs(got) == published and LAGGED not in [p.kind for p in got]
    assert [json.loads(p.text)["seq"] for p in got] == published  # the text is the message
    behind = len(published) > size
    assert (slow_got[-1].kind == LAGGED) == behind
    if behind:
        notice = json.loads(slow_got[-1].text)
        assert notice["missed"] >= 1 and "reconnect" in notice["detail"]
    assert _seqs(slow_got) == published[: len(_seqs(slow_got))]  # in order, none skipped


def test_events_from_threads_reach_every_client_once_each_in_publish_order() -> None:
    feed = EventFeed(queue_size=1000)
    count, clients = 300, 50

    async def run() -> list[list[int]]:
        loop = asyncio.get_running_loop()
        subs = [feed.subscribe(loop)[0] for _ in range(clients)]
        publishers = [
            threading.Thread(target=lambda: [feed.publish("e", {}) for _ in range(count // 3)])
            for _ in range(3)
        ]
        for t in publishers:
            t.start()

        async def read(sub: object) -> list[int]:
            seen: list[int] = []
            while len(seen) < count:
                seen += _seqs(await sub.next(timeout=60))  # type: ignore[attr-defined]
            return seen

        seen = await asyncio.gather(*(read(s) for s in subs))
        for t in publishers:
            t.join()
        return list(seen)

    for seen in asyncio.run(run()):
        assert seen == list(range(1, count + 1))


def test_publishing_serializes_once_whatever_the_number_of_clients() -> None:
    encoded: list[str] = []

    def scrub(text: str) -> str:
        encoded.append(text)
        return text.replace("s3cret", "***")

    feed = EventFeed(scrub=scrub)

    async def run() -> list[list[Packet]]:
        loop = asyncio.get_running_loop()
        subs = [feed.subscribe(loop)[0] for _ in range(100)]
        feed.publish("state", {"note": "s3cret"})
        return [await s.next(timeout=60) for s in subs]

    received = asyncio.run(run())
    assert len(encoded) == 1  # once per event, not once per client
    assert all(r[0] is received[0][0] and "***" in r[0].text for r in received)


def test_a_closed_subscription_stops_waiting_and_is_forgotten() -> None:
    feed = EventFeed()

    async def run() -> list[Packet]:
        sub, _ = feed.subscribe(asyncio.get_running_loop())
        waiting = asyncio.ensure_future(sub.next())
        await asyncio.sleep(0)
        sub.close()
        return await asyncio.wait_for(waiting, 60)

    assert asyncio.run(run()) == [] and feed.clients == 0


@settings(max_examples=25, deadline=None)
@given(
    clients=st.integers(1, 120),
    publish_turns=st.lists(st.integers(1, 20), min_size=1, max_size=12),
    limit=st.integers(1, 5),
)
def test_a_loop_turn_runs_at_most_one_slice_of_clients_whatever_is_published(
    clients: int, publish_turns: list[int], limit: int
) -> None:
    """Events published while the clients are being woken (a mission's events come in bursts)
    never make one event-loop turn run more than WAKE_SLICE clients, nor hand them more than
    `limit` messages each: whatever else the loop has to do, an e-stop request above all, waits
    for one slice at most, however far behind the clients are. Every client still gets every
    event, in order."""
    feed = EventFeed(queue_size=1000)
    events = len(publish_turns)

    async def run() -> tuple[list[set[int]], list[int], list[list[int]]]:
        loop = asyncio.get_running_loop()
        subs = [feed.subscribe(loop)[0] for _ in range(clients)]
        ran: list[set[int]] = [set()]  # per loop turn: the clients that ran in it
        sent = [0]  # per loop turn: the messages they got
        done = asyncio.Event()

        def tick() -> None:  # runs once per loop turn, ahead of the clients woken in it
            ran.append(set())
            sent.append(0)
            for _ in range(publish_turns.count(len(ran) - 1)):
                feed.publish("step", {"turn": len(ran) - 1})
            if not done.is_set():
                loop.call_soon(tick)

        async def read(index: int, sub: Subscription) -> list[int]:
            seen: list[int] = []
            while len(seen) < events:
                packets = await sub.next(limit=limit)
                ran[-1].add(index)
                sent[-1] += len(packets)
                seen += _seqs(packets)
            return seen

        readers = [asyncio.ensure_future(read(i, s)) for i, s in enumerate(subs)]
        await asyncio.sleep(0)  # every reader waits for its first event
        loop.call_soon(tick)
        seen = await asyncio.gather(*readers)
        done.set()
        return ran, sent, list(seen)

    ran, sent, seen = asyncio.run(asyncio.wait_for(run(), 120))
    assert all(s == list(range(1, events + 1)) for s in seen)
    assert max(len(r) for r in ran) <= WAKE_SLICE, [len(r) for r in ran]
    assert max(sent) <= WAKE_SLICE * limit, sent
