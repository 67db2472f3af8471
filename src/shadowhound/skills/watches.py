"""Watches: conditions a step's runtime checks at control rate (never a model).

A plan step may carry watches (`plan.Watch`): "until the red ball is seen" ends the step when it
holds and the mission goes on; "unless something is in the way" stops the step and ends the
mission there, saying why. The plan is checked as if no watch ever fired, and a watch can only
stop motion, so it never takes the robot anywhere the governor did not allow.

`check_watches` refuses, before anything moves, a watch the robot cannot observe (no camera
that labels what is in view, no range sensor, no battery reading) or that names something it
cannot recognise: a condition a person stated is honoured or the mission refused, never
dropped. `Watcher` evaluates a step's watches each tick over one reading of what they need.
"""

from __future__ import annotations

import logging
import math
from collections.abc import Sequence
from dataclasses import dataclass

from ..errors import WatchFired
from ..plan import GUARD_WHEN, WATCH_KINDS, WATCH_WHEN, Watch, branches
from ..robot.base import Robot, RobotError
from ..state import RobotState, Scan, Sighting
from ..world.objects import object_key

MAX_NAME = 60  # characters of a watched thing's name
IN_THE_WAY = (0.3, 5.0)  # metres from the body a path check may reach
SEEN_WITHIN = (0.2, 20.0)  # metres a "seen within" may ask
_CORRIDOR = 0.15  # metres either side of the body a return still counts as in the path

__all__ = ["GUARD_WHEN", "Branches", "Watcher", "check_watches", "fired_text", "guard_holds"]

log = logging.getLogger(__name__)


def check_watches(
    watches: Sequence[Watch],
    robot: Robot,
    vocabulary: frozenset[str] | None,
    allowed: tuple[str, ...] = WATCH_WHEN,
) -> list[str]:
    """Why these watches (or, with `allowed` GUARD_WHEN, guards) cannot be honoured on
    `robot` (empty: they can)."""
    problems: list[str] = []
    for w in watches:
        if not isinstance(w, Watch):
            problems.append(f"a watch must be a condition, got {type(w).__name__}")
            continue
        if w.when not in allowed:
            problems.append(f"a condition here is {' or '.join(allowed)}, not {w.when!r}")
        if w.kind not in WATCH_KINDS:
            problems.append(
                f"cannot watch for {w.words or w.kind!r}: a watch is one of "
                f"{', '.join(WATCH_KINDS)}"
            )
            continue
        problems += _observable(w, robot, vocabulary)
    return problems


def _observable(w: Watch, robot: Robot, vocabulary: frozenset[str] | None) -> list[str]:
    said = f"'{w.words}'" if w.words else w.describe()
    if w.kind == "seen":
        name = object_key(w.name)
        if not name or len(name) > MAX_NAME:
            return [f"{said}: name what to watch for (1 to {MAX_NAME} characters)"]
        if w.within is not None and not SEEN_WITHIN[0] <= w.within <= SEEN_WITHIN[1]:
            return [f"{said}: 'within' must be {SEEN_WITHIN[0]:g} to {SEEN_WITHIN[1]:g} m"]
        if robot.in_view() is None:
            return [f"cannot watch {said}: {robot.description} cannot tell what is in view"]
        if vocabulary is not None and not _known(name, vocabulary):
            known = ", ".join(sorted(vocabulary)) or "nothing"
            return [f"cannot watch {said}: the camera recognises {known}"]
        return []
    if w.kind == "in_the_way":
        low, high = IN_THE_WAY
        if w.within is None or not low <= w.within <= high:
            return [f"{said}: how far ahead to watch must be {low:g} to {high:g} m"]
        if robot.get_scan() is None:
            return [f"cannot watch {said}: {robot.description} has no range sensor (scan)"]
        return []
    if w.kind == "operator_stop":
        return []  # every interface can stop a mission
    if w.percent is None or not 0 < w.percent < 100:
        return [f"{said}: the battery level must be a percent between 0 and 100"]
    if robot.last_state().battery is None:
        return [f"cannot watch {said}: {robot.description} reports no battery level"]
    return []


def _known(name: str, vocabulary: frozenset[str]) -> bool:
    keys = {object_key(v) for v in vocabulary}
    return name in keys or any(k.endswith(" " + name) for k in keys)


def names(name: str, seen: str) -> bool:
    """`name` ("ball", "the red ball") names the thing `seen` ("red ball")."""
    key = object_key(seen)
    return key == name or key.endswith(" " + name)


@dataclass(frozen=True)
class _Reading:
    """What the watches of one tick need, read once."""

    state: RobotState
    in_view: tuple[Sighting, ...]
    scan: Scan | None


@dataclass(frozen=True)
class _Seen:
    """One tick's reading as the watches compare it, worked out once for all of them: each
    sighting's name as names compare, and the scan's returns in the robot's path."""

    keys: tuple[str, ...]  # object_key of each sighting in view
    in_path: tuple[tuple[float, float], ...]  # (range, metres ahead) of returns in the path


class Watcher:
    """A step's watches over `robot`: `fired(state)` returns the first that holds now, with
    what was observed, or None. Reads only what its watches need (the view, the scan) once a
    tick, and passes over the scan once a tick whatever the number of watches (a plan carries
    at most `agent.max_watches_per_step` on a step). `heading` (body frame, radians) is where
    the robot goes: the path a path check looks along."""

    def __init__(self, watches: Sequence[Watch], robot: Robot, body_radius: float) -> None:
        self.watches = tuple(watches)
        self.robot = robot
        self.body_radius = body_radius
        # The view names what is in the way too: read once a tick for either.
        self._view = any(w.kind in ("seen", "in_the_way") for w in self.watches)
        reaches = [w.within for w in self.watches if w.kind == "in_the_way" and w.within]
        self._reach = body_radius + max(reaches) if reaches else None  # None: no scan read
        self._keys = {id(w): object_key(w.name) for w in self.watches}

    def fired(self, state: RobotState, heading: float | None) -> tuple[Watch, str] | None:
        if not self.watches:
            return None
        reading = _Reading(
            state,
            (self.robot.in_view() or ()) if self._view else (),
            self.robot.get_scan() if self._reach is not None else None,
        )
        return self.evaluate(reading, heading)

    def evaluate(self, r: _Reading, heading: float | None) -> tuple[Watch, str] | None:
        seen = _Seen(
            tuple(object_key(s.name) for s in r.in_view),
            self._in_path(r.scan, r.state, heading) if r.scan is not None else (),
        )
        for w in self.watches:
            observed = self._holds(w, r, seen, heading)
            if observed:
                return w, observed
        return None

    def _holds(self, w: Watch, r: _Reading, seen: _Seen, heading: float | None) -> str:
        if w.kind == "seen":
            key = self._keys[id(w)]
            for s, name in zip(r.in_view, seen.keys, strict=True):
                if (name == key or name.endswith(" " + key)) and (
                    w.within is None or s.distance <= w.within
                ):
                    return f"saw {s.describe()}"
            return ""
        if w.kind == "in_the_way":
            return self._in_the_way(w, r, seen, heading)
        if w.kind == "operator_stop":
            return ""  # a person's stop arrives as the mission's cancel (mission.run_step)
        battery = r.state.battery
        if battery is not None and w.percent is not None and battery < w.percent:
            return f"the battery is at {battery:.0f}%, below {w.percent:g}%"
        return ""

    def _in_path(
        self, scan: Scan, state: RobotState, heading: float | None
    ) -> tuple[tuple[float, float], ...]:
        """The scan's returns within the farthest reach any watch asks, in the body's path
        along `heading`: (range, metres ahead), read in one pass."""
        if self._reach is None:
            return ()
        along = 0.0 if heading is None else heading  # body frame: 0 = straight ahead
        half = self.body_radius + _CORRIDOR
        rel = scan.pose.yaw - state.yaw  # the scan's frame against the body's
        top = min(self._reach, scan.range_max)
        found = []
        for i, d in enumerate(scan.ranges):
            if not scan.range_min <= d <= top:
                continue
            a = scan.angle_min + i * scan.angle_increment + rel - along
            ahead, side = d * math.cos(a), d * math.sin(a)
            if ahead > 0 and abs(side) <= half:
                found.append((d, ahead))
        return tuple(found)

    def _in_the_way(self, w: Watch, r: _Reading, seen: _Seen, heading: float | None) -> str:
        if w.within is None:
            return ""
        reach = self.body_radius + w.within
        nearest = min((ahead for d, ahead in seen.in_path if d <= reach), default=math.inf)
        if nearest == math.inf:
            return ""
        along = 0.0 if heading is None else heading
        gap = max(0.0, nearest - self.body_radius)
        what = self._named(r, nearest, along)
        return f"{what} in the way {gap:.2f} m ahead"

    def _named(self, r: _Reading, distance: float, along: float) -> str:
        """What the camera shows near the return (this tick's view), else "something"."""
        for s in r.in_view:
            if abs(s.distance - distance) < 0.6 and abs(math.radians(s.bearing_deg) - along) < 0.5:
                return s.name
        return "something"


def fired_text(w: Watch, observed: str) -> str:
    """The step's words when `w` fired: "stopped: saw red ball about 2.3 m ahead (until you
    see the red ball)": what was observed, and the person's words for the condition."""
    return f"stopped: {observed} ({w.words or w.describe()})"


def raise_if_fired(watcher: Watcher | None, state: RobotState, heading: float | None) -> None:
    """Stop the robot and raise WatchFired when one of the step's watches holds."""
    if watcher is None:
        return
    hit = watcher.fired(state, heading)
    if hit is not None:
        watcher.robot.stop()
        raise WatchFired(hit[0], hit[1])


class Branches:
    """The branches of one batch of steps (`plan.branches`), each decided once, when its first
    step is reached: every step of a branch follows that decision, so one way runs, never
    both, whatever the first way did to what the condition reads. A condition that cannot be
    read decides nothing: every step of its branch is skipped."""

    def __init__(self, guards: Sequence[Watch | None], robot: Robot, body_radius: float) -> None:
        self._of = branches(guards)
        self._robot, self._body_radius = robot, body_radius
        self._decided: dict[int, tuple[bool | None, str]] = {}  # did it hold, and why

    def runs(self, position: int, guard: Watch) -> tuple[bool, str]:
        """Whether the step at `position`, guarded by `guard`, runs, and why in words."""
        branch = self._of[position]
        later = branch in self._decided
        if not later:
            self._decided[branch] = self._decide(guard)
        holds, why = self._decided[branch]
        said = f"{why} ({guard.words or guard.describe()})"
        if later:
            said += ", decided when the branch began"
        return holds is not None and holds == (guard.when == "if"), said

    def _decide(self, guard: Watch) -> tuple[bool | None, str]:
        try:
            runs, why = guard_holds(guard, self._robot, self._body_radius)
        except RobotError as exc:
            return None, f"the condition could not be read: {exc}"
        except Exception as exc:  # a bug must not end the mission uncaught: skip, say so
            log.exception("guard %r crashed", guard)
            return None, f"internal error reading the condition: {exc!r}"
        return runs == (guard.when == "if"), why


def guard_holds(guard: Watch, robot: Robot, body_radius: float) -> tuple[bool, str]:
    """Whether a step guarded by `guard` runs now, and why in words ("the battery is at 25%,
    below 30%" / "the battery is not below 30%"). A path check looks straight ahead."""
    state = robot.get_state()
    hit = Watcher([guard], robot, body_radius).fired(state, 0.0)
    runs = (hit is not None) == (guard.when == "if")
    return runs, hit[1] if hit is not None else _not_so(guard, state)


def _not_so(guard: Watch, state: RobotState) -> str:
    """Why a guard's condition does not hold now, in words."""
    if guard.kind == "battery_below":
        return f"the battery is at {state.battery_text}, not below {guard.percent or 0:g}%"
    if guard.kind == "seen":
        near = f" within {guard.within:g} m" if guard.within is not None else ""
        return f"no {guard.name} in view{near}"
    return f"nothing in the way within {guard.within or 0:g} m"
