"""When each odometry pose was sent, on this process's clock: the driver's stamps read
against the link's jitter (a pure-Python helper of the Go2's odometry intake)."""

from __future__ import annotations

import math
from collections import deque


class StampClock:
    """When each odometry pose was *sent*, on this process's monotonic clock.

    A pose's arrival time carries the link's jitter (a busy Wi-Fi link, a starved process):
    a pose that arrives 0.3 s later than usual, read as new, puts a turning robot 10 degrees
    off. The driver stamps each message when it publishes it, on its own clock, which need not
    agree with ours (another computer, ROS time vs monotonic). The offset between the clocks
    is the smallest `arrival - stamp` seen over the last `window` seconds (the sample that
    crossed fastest); a stamp plus that offset is the time the sample would have arrived
    without jitter. The steady part of the delay stays in the tracker's measured latency.

    Falls back to the arrival time when a message carries no stamp (0) and starts over when
    the sender's clock jumps. Times returned never go backwards.
    """

    def __init__(self, window: float = 10.0, jump: float = 5.0) -> None:
        self.window, self.jump = window, jump
        self._gaps: deque[tuple[float, float]] = deque()  # (arrival, arrival - stamp)
        self._last = -math.inf

    def local_time(self, stamp: float, arrival: float) -> float:
        if not (math.isfinite(stamp) and stamp > 0):
            t = arrival
        else:
            gap = arrival - stamp
            if self._gaps and abs(gap - self.offset) > self.jump:
                self._gaps.clear()  # the sender's clock was set: old offsets mean nothing
            while self._gaps and self._gaps[-1][1] >= gap:
                self._gaps.pop()  # never the minimum again: a smaller gap came later
            self._gaps.append((arrival, gap))
            while arrival - self._gaps[0][0] > self.window:
                self._gaps.popleft()
            t = min(arrival, stamp + self.offset)
        self._last = max(self._last, t)
        return self._last

    @property
    def offset(self) -> float:
        """Seconds to add to a stamp (only meaningful once a stamped sample arrived)."""
        return self._gaps[0][1] if self._gaps else 0.0
