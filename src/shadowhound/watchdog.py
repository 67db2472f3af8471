"""The watchdog: zero velocity when the control loop stops ticking while the robot moves.

A stalled loop (a loaded machine) goes on from rest when it comes back within the grace; a hung
one (a skill's bug, a stalled model) stops its mission. See docs/safety.md, item 6.
"""

from __future__ import annotations

import logging
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass

log = logging.getLogger(__name__)


@dataclass(frozen=True)
class Trip:
    """The watchdog stopped the robot: `stalled` seconds went by without a control tick
    before it did, `ago` seconds before the control loop heard of it (its next beat)."""

    stalled: float
    ago: float


class Watchdog:
    """Zeroes the robot's velocity when the control loop stops ticking while it moves.

    Skills beat through their SkillContext on every tick and command. A daemon thread checks
    every `timeout / 5`; when the last command was a motion and no beat came for `timeout`
    seconds, it calls `stop`. That is all a stall needs: a loaded machine (SLAM, Nav2 and a
    detector beside ShadowHound) holds a control loop up for a fraction of a second now and
    then, and the loop's next beat learns of the stop (`beat` returns the `Trip`) and goes on
    from rest. A loop that does not beat again within `grace` seconds of the stop is hung (a
    skill's bug, a stalled model): `on_trip` reports it and the mission stops.
    The thread starts when the watchdog is first armed: an agent whose robot never needs
    guarding (a simulator at time scale 0) runs none.
    """

    def __init__(self, stop: Callable[[], None], on_trip: Callable[[str], None]) -> None:
        self._stop = stop
        self._on_trip = on_trip
        self._lock = threading.Lock()
        self._stopping = threading.Lock()  # held while the stop goes out: a beat waits for it
        self._last = time.monotonic()
        self._moving = False
        self._armed = False
        self.timeout = 0.25
        self.grace = 2.0
        self.trips = 0  # stops, the loop back or not
        self.hangs = 0  # loops that did not come back within the grace
        self._tripped: tuple[float, float] | None = None  # (stalled for, stopped at), unheard
        self._closed = threading.Event()
        self._thread = threading.Thread(target=self._run, name="shadowhound-watchdog", daemon=True)

    def arm(self, timeout: float, grace: float = 2.0) -> None:
        with self._lock:
            self.timeout, self.grace, self._armed, self._last, self._moving = (
                timeout,
                grace,
                True,
                time.monotonic(),
                False,
            )
            self._tripped = None
            if self._thread.ident is None and not self._closed.is_set():
                self._thread.start()

    def disarm(self) -> None:
        with self._lock:
            self._armed = False
            self._tripped = None

    def beat(self, moving: bool | None = None) -> Trip | None:
        """The control loop ticked (and commands motion or not, when `moving` is given).
        Returns the `Trip` when the watchdog stopped the robot since the last beat, once."""
        with self._stopping, self._lock:  # a stop under way has gone out before this returns
            now = time.monotonic()
            self._last = now
            if moving is not None:
                self._moving = moving
            tripped, self._tripped = self._tripped, None
        if tripped is None:
            return None
        stalled, at = tripped
        return Trip(stalled, now - at)

    def close(self) -> None:
        """End the watchdog's thread (within one check period)."""
        with self._lock:
            self._closed.set()
            started = self._thread.ident is not None
        if started:
            self._thread.join(1.0)

    def _run(self) -> None:
        while not self._closed.wait(max(0.005, self.timeout / 5)):
            with self._stopping:
                with self._lock:
                    now = time.monotonic()
                    stale = now - self._last
                    tripped = self._armed and self._moving and stale > self.timeout
                    if tripped:
                        self._moving = False
                        self.trips += 1
                        self._tripped = (stale, now)
                    hung = (
                        self._armed
                        and self._tripped is not None
                        and now - self._tripped[1] > self.grace
                    )
                    if hung:
                        assert self._tripped is not None
                        stalled = self._tripped[0] + now - self._tripped[1]
                        self._tripped = None
                        self.hangs += 1
                if tripped:
                    self._stop()
                    log.warning(
                        "watchdog: no control tick for %.2f s while the robot was moving; "
                        "velocity set to zero (the loop goes on if it comes back within %g s)",
                        stale,
                        self.grace,
                    )
            if hung:
                self._on_trip(
                    f"watchdog: no control tick for {stalled:.2f} s while the robot was moving "
                    f"(stopped after safety.watchdog_timeout, {self.timeout:g} s; the control "
                    f"loop did not come back within safety.watchdog_grace, {self.grace:g} s); "
                    "velocity set to zero"
                )
