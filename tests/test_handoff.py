"""Work handed off a ROS executor (robot/handoff.py): the newest messages kept, in order, read
one at a time on a thread of its own, which a failing read does not end."""

from __future__ import annotations

import threading
import time
from collections.abc import Callable

from shadowhound.robot.handoff import Handoff


def wait_until(predicate: Callable[[], bool], timeout: float, what: str) -> None:
    deadline = time.monotonic() + timeout
    while not predicate():
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.005)


class Reader:
    """Takes items; the first waits until `release` (the thread is busy meanwhile)."""

    def __init__(self) -> None:
        self.taken: list[int] = []
        self.busy, self.release = threading.Event(), threading.Event()

    def __call__(self, item: int) -> None:
        if not self.taken:
            self.busy.set()
            self.release.wait(10)
        if item < 0:
            raise ValueError("a message that cannot be read")
        self.taken.append(item)


def run(depth: int, items: list[int]) -> tuple[list[int], int]:
    """Offer 0, then `items` while 0 is being read: what was read, and how many replaced."""
    reader = Reader()
    handoff = Handoff(reader, "test-handoff", depth)
    handoff.offer(0)
    reader.busy.wait(10)
    for item in items:
        handoff.offer(item)
    reader.release.set()
    kept = [i for i in items if i >= 0][-depth:] if depth else []
    wait_until(lambda: reader.taken[-1:] == kept[-1:], 10, "the newest item read")
    handoff.close()
    return reader.taken, handoff.replaced


def test_depth_one_reads_the_newest_only() -> None:
    assert run(1, [1, 2, 3]) == ([0, 3], 2)


def test_a_deeper_handoff_reads_in_order_and_drops_the_oldest() -> None:
    assert run(3, [1, 2, 3, 4, 5]) == ([0, 3, 4, 5], 2)
    assert run(100, [1, 2]) == ([0, 1, 2], 0)


def test_a_read_that_fails_does_not_end_the_thread() -> None:
    assert run(3, [-1, 7]) == ([0, 7], 0)
