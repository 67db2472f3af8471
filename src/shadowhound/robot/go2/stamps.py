"""Header stamps of what the Go2 robot reads from ROS, judged on this process's clocks (pure
Python):

- `StampWindow`: which stamps a message may carry, on this computer's ROS clock. Inputs kept
  "latest by stamp" (TF's history, SLAM's newest map -> odom, sightings, boxes waiting for
  their odometry) would let one stamp from the future win over every honest one after it, so a
  stamp too far ahead (or too old to describe anything kept) is refused, and said why;
- `StampClock`: when each odometry pose was sent, the driver's stamps read against the link's
  jitter (the driver's clock need not agree with ours: odometry is not judged by the window).
"""

from __future__ import annotations

import math
from collections import deque
from dataclasses import dataclass

# Seconds a stamp may be ahead of this computer's clock. Honest senders post-date: AMCL stamps
# map -> odom `transform_tolerance` (1 s by default) ahead, slam_toolbox `transform_timeout`
# (0.2 s); synchronised computers differ by milliseconds. A stamp within this bound can hold off
# honest samples for at most this long.
STAMP_AHEAD = 2.0
STAMP_BEHIND = 10.0  # seconds: older than any history kept (TF's, the poses boxes are placed by)


@dataclass(frozen=True)
class StampWindow:
    """The stamps an input may carry: from `behind` seconds before this computer's clock (ROS
    time, which the robot's driver, SLAM and detector share with it) to `ahead` after."""

    ahead: float = STAMP_AHEAD
    behind: float = STAMP_BEHIND

    def problem(self, stamp: float, now: float) -> str | None:
        """Why `stamp` is refused at `now` (both seconds of ROS time), or None."""
        if not math.isfinite(stamp):
            return f"its stamp {stamp!r} is not a time"
        if stamp > now + self.ahead:
            return (
                f"stamped {stamp - now:.1f} s ahead of this computer's clock (at most "
                f"{self.ahead:g} s is taken: a clock set wrong, or a forged message)"
            )
        if stamp < now - self.behind:
            return (
                f"stamped {now - stamp:.1f} s before this computer's clock (at most "
                f"{self.behind:g} s is taken: clocks not synchronised, or a replayed message)"
            )
        return None


STAMPS = StampWindow()  # the window every stamped input of the robot is judged by


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
