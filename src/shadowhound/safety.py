"""The safety governor: limits every skill call must pass before it reaches the robot.

Whoever proposed a step (a planner, the web, a test), the agent checks the whole plan here
before the first step runs, predicting the robot's pose and posture step by step. A plan with
any refused step is refused whole; risky steps run only with approval. `SkillContext.drive`
additionally caps every velocity and acceleration command, the agent's watchdog zeroes velocity
when the control loop stops ticking, and the agent checks each motion step's measured outcome.
"""

from __future__ import annotations

import fnmatch
import math
import threading
import time
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field

from .config import SafetyConfig
from .robot.go2_api import TRICKS
from .skills.context import PlanEnv, PlanProblem
from .skills.registry import ValidatedCall
from .state import Pose2D, Posture, RobotState, normalize_angle

# What may still run when the battery is below the floor: nothing that walks.
LOW_BATTERY_SKILLS = ("nav.stop", "body.sit", "body.lie_down", "sys.status")
_POSTURE_OF = {"body.stand": Posture.STANDING, "body.sit": Posture.SITTING,
               "body.lie_down": Posture.LYING}


@dataclass(frozen=True)
class Refusal:
    """Why one step may not run (or may run only with approval). `step` is 1-based."""

    step: int
    skill: str
    reason: str

    def __str__(self) -> str:
        return f"step {self.step} ({self.skill}): {self.reason}"


@dataclass
class PlanCheck:
    """The governor's verdict on a plan and the path it predicts (start pose first)."""

    refusals: list[Refusal] = field(default_factory=list)
    approvals: list[Refusal] = field(default_factory=list)
    path: list[Pose2D] = field(default_factory=list)
    distance: float = 0.0
    notes: list[str] = field(default_factory=list)  # what the check could not establish


class Governor:
    """Checks steps against `SafetyConfig`. Stateless apart from its limits."""

    def __init__(self, limits: SafetyConfig, auto_stand: bool = True) -> None:
        self.limits = limits
        self.auto_stand = auto_stand

    def check_plan(
        self, calls: Sequence[ValidatedCall | None], start: RobotState, env: PlanEnv
    ) -> PlanCheck:
        """Check every step from `start`. None stands for a step that failed validation: it
        is skipped and the rest still checked."""
        check = PlanCheck(path=[start.pose])
        if start.battery is None:  # say so, rather than pass a level nobody measured
            check.notes.append(f"battery level unknown (the robot reports none): the battery "
                               f"floor of {self.limits.battery_floor:g}% "
                               "(safety.battery_floor) cannot be checked")
        pose, posture = start.pose, start.posture
        for index, call in enumerate(calls, start=1):
            if call is None:
                continue
            try:
                reasons, poses, needs_approval = self._check(call, pose, posture, start, env)
            except PlanProblem as exc:
                check.refusals.append(Refusal(index, call.name, str(exc)))
                continue
            legs = _legs(pose, poses)
            check.distance += sum(legs)
            if check.distance > self.limits.max_mission_distance + 1e-9:
                reasons.append(
                    f"the mission would travel {check.distance:.1f} m, more than the limit of "
                    f"{self.limits.max_mission_distance:g} m (safety.max_mission_distance)"
                )
            check.refusals += [Refusal(index, call.name, r) for r in reasons]
            if needs_approval:
                check.approvals.append(Refusal(index, call.name, needs_approval))
            check.path.extend(poses)
            pose = poses[-1] if poses else pose
            posture = _POSTURE_OF.get(call.name, Posture.STANDING if call.skill.moves or
                                      call.name == "body.sport" else posture)
        return check

    def check_outcome(self, call: ValidatedCall, before: RobotState, after: RobotState,
                      env: PlanEnv) -> str:
        """Compare where a motion step should have ended with where the robot measurably is.

        Returns why the outcome is off ("" when it is within tolerance): a step whose robot did
        not get there is reported failed, never as done.
        """
        if not call.skill.moves or call.skill.predict is None:
            return ""
        expected = call.skill.predict(before.pose, call.args, env)
        if not expected:
            return ""
        want = expected[-1]
        off = math.hypot(after.x - want.x, after.y - want.y)
        turn = abs(math.degrees(normalize_angle(after.yaw - want.yaw)))
        lim = self.limits
        if off <= lim.outcome_tolerance and turn <= lim.outcome_tolerance_deg:
            return ""
        return (f"outcome check failed: expected to end at ({want.x:.2f}, {want.y:.2f}, "
                f"{math.degrees(want.yaw):.0f} deg) but measured ({after.x:.2f}, {after.y:.2f}, "
                f"{math.degrees(after.yaw):.0f} deg): {off:.2f} m and {turn:.0f} degrees off "
                "(safety.outcome_tolerance, outcome_tolerance_deg)")

    def check_step(self, call: ValidatedCall, state: RobotState, env: PlanEnv) -> list[str]:
        """Re-check one step from the measured state just before it runs."""
        try:
            return self._check(call, state.pose, state.posture, state, env)[0]
        except PlanProblem as exc:
            return [str(exc)]

    def _check(
        self, call: ValidatedCall, pose: Pose2D, posture: Posture, start: RobotState,
        env: PlanEnv,
    ) -> tuple[list[str], list[Pose2D], str]:
        lim = self.limits
        name, args = call.name, call.args
        reasons: list[str] = []
        if lim.allow_skills is not None and not _matches(name, lim.allow_skills):
            reasons.append(f"{name} is not in safety.allow_skills ({', '.join(lim.allow_skills)})")
        if _matches(name, lim.deny_skills):
            reasons.append(f"{name} is in safety.deny_skills")
        level = start.battery  # None: unknown, said once in check_plan's notes
        if level is not None and level < lim.battery_floor and name not in LOW_BATTERY_SKILLS:
            reasons.append(
                f"the battery is at {level:.0f}%, below the floor of "
                f"{lim.battery_floor:g}% (safety.battery_floor): only "
                f"{', '.join(LOW_BATTERY_SKILLS)} are allowed"
            )
        speed = getattr(args, "speed", None)
        if speed is not None:
            rotate = name == "nav.rotate"
            cap = lim.max_angular_speed if rotate else lim.max_linear_speed
            unit, setting = ("rad/s", "max_angular_speed") if rotate else \
                ("m/s", "max_linear_speed")
            if speed > cap:
                reasons.append(f"speed {speed:g} {unit} exceeds the cap of {cap:g} {unit} "
                               f"(safety.{setting})")
        seconds = getattr(args, "seconds", None)
        if seconds is not None and seconds > lim.max_wait:
            reasons.append(f"waiting {seconds:g} s exceeds safety.max_wait ({lim.max_wait:g} s)")
        needs_standing = call.skill.moves or name == "body.sport"
        if needs_standing and posture is not Posture.STANDING and not self.auto_stand:
            reasons.append(f"the robot will be {posture.value} here; add body.stand before it "
                           "(motion.auto_stand is off)")
        approval = ""
        trick = getattr(args, "trick", None)
        if trick is not None and TRICKS[trick].risky and not lim.allow_risky_tricks:
            approval = (f"{trick} is a risky trick (it can hurt people or the robot) and needs "
                        "approval, or safety.allow_risky_tricks: true")
        poses = call.skill.predict(pose, args, env) if call.skill.predict else []
        for leg in _legs(pose, poses):
            if leg > lim.max_step_distance + 1e-9:
                reasons.append(
                    f"a straight leg of {leg:.2f} m exceeds the limit of "
                    f"{lim.max_step_distance:g} m per step (safety.max_step_distance)"
                )
                break
        outside = self._outside_fence(pose, poses)
        if outside:
            reasons.append(outside)
        return reasons, poses, approval

    def _outside_fence(self, pose: Pose2D, poses: list[Pose2D]) -> str:
        lim = self.limits
        previous = pose
        for p in poses:
            if math.hypot(p.x, p.y) > lim.geofence_radius + 1e-9:
                return (f"it would take the robot to ({p.x:.2f}, {p.y:.2f}), outside the "
                        f"geofence of {lim.geofence_radius:g} m around the origin "
                        "(safety.geofence_radius)")
            polygon = lim.geofence_polygon
            if polygon and (not inside_polygon(p.x, p.y, polygon)
                            or _crosses(previous, p, polygon)):
                return (f"its path to ({p.x:.2f}, {p.y:.2f}) leaves the geofence polygon "
                        "(safety.geofence_polygon)")
            previous = p
        return ""


def inside_polygon(x: float, y: float, polygon: Sequence[tuple[float, float]]) -> bool:
    """Even-odd rule; points on an edge count as inside."""
    inside = False
    n = len(polygon)
    for i in range(n):
        (x1, y1), (x2, y2) = polygon[i], polygon[(i + 1) % n]
        if _on_segment(x, y, x1, y1, x2, y2):
            return True
        if (y1 > y) != (y2 > y) and x < x1 + (y - y1) * (x2 - x1) / (y2 - y1):
            inside = not inside
    return inside


def _crosses(a: Pose2D, b: Pose2D, polygon: Sequence[tuple[float, float]]) -> bool:
    """Does the straight leg a->b properly cross any edge (a non-convex fence)?"""
    n = len(polygon)
    for i in range(n):
        (x1, y1), (x2, y2) = polygon[i], polygon[(i + 1) % n]
        d1 = _cross(x1, y1, x2, y2, a.x, a.y)
        d2 = _cross(x1, y1, x2, y2, b.x, b.y)
        d3 = _cross(a.x, a.y, b.x, b.y, x1, y1)
        d4 = _cross(a.x, a.y, b.x, b.y, x2, y2)
        if d1 * d2 < -1e-12 and d3 * d4 < -1e-12:
            return True
    return False


def _cross(ax: float, ay: float, bx: float, by: float, px: float, py: float) -> float:
    return (bx - ax) * (py - ay) - (by - ay) * (px - ax)


def _on_segment(px: float, py: float, x1: float, y1: float, x2: float, y2: float) -> bool:
    if abs(_cross(x1, y1, x2, y2, px, py)) > 1e-9:
        return False
    return min(x1, x2) - 1e-9 <= px <= max(x1, x2) + 1e-9 and \
        min(y1, y2) - 1e-9 <= py <= max(y1, y2) + 1e-9


def _legs(pose: Pose2D, poses: list[Pose2D]) -> list[float]:
    points = [pose, *poses]
    return [math.hypot(b.x - a.x, b.y - a.y) for a, b in zip(points, points[1:], strict=False)]


def _matches(name: str, patterns: Sequence[str]) -> bool:
    return any(fnmatch.fnmatchcase(name, p) for p in patterns)


class Watchdog:
    """Zeroes the robot's velocity when the control loop stops ticking while it moves.

    Skills beat through their SkillContext on every tick and command. A daemon thread checks
    every `timeout / 5`; when the last command was a motion and no beat came for `timeout`
    seconds (a hung skill, a stalled model), it calls `stop` and reports through `on_trip`.
    """

    def __init__(self, stop: Callable[[], None], on_trip: Callable[[str], None]) -> None:
        self._stop = stop
        self._on_trip = on_trip
        self._lock = threading.Lock()
        self._last = time.monotonic()
        self._moving = False
        self._armed = False
        self.timeout = 0.25
        self.trips = 0
        self._closed = threading.Event()
        self._thread = threading.Thread(target=self._run, name="shadowhound-watchdog",
                                        daemon=True)
        self._thread.start()

    def arm(self, timeout: float) -> None:
        with self._lock:
            self.timeout, self._armed, self._last, self._moving = timeout, True, \
                time.monotonic(), False

    def disarm(self) -> None:
        with self._lock:
            self._armed = False

    def beat(self, moving: bool | None = None) -> None:
        with self._lock:
            self._last = time.monotonic()
            if moving is not None:
                self._moving = moving

    def close(self) -> None:
        """End the watchdog's thread (within one check period)."""
        self._closed.set()
        self._thread.join(1.0)

    def _run(self) -> None:
        while not self._closed.wait(max(0.005, self.timeout / 5)):
            with self._lock:
                stale = time.monotonic() - self._last
                tripped = self._armed and self._moving and stale > self.timeout
                if tripped:
                    self._moving = False
                    self.trips += 1
            if tripped:
                self._stop()
                self._on_trip(f"watchdog: no control tick for {stale:.2f} s while the robot "
                              "was moving; velocity set to zero")
