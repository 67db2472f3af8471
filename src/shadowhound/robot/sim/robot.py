"""SimRobot: a kinematic Unitree Go2 with its own clock. A real robot for development and tests.

Physics: body-frame velocity follows the command within the Go2's acceleration and velocity
limits; the pose integrates in the odom frame. Postures form a small state machine:

    standing <-> sitting, standing <-> lying, sitting <-> lying (through standing)

Like the real Go2, velocity commands are *ignored* while sitting or lying (they are recorded
with accepted=False); the motion skills stand the robot up first (MotionConfig.auto_stand).
Tricks run only while standing and never translate the robot.

With SimConfig.collisions the body is a circle (body_radius) in the scene (robot/scene.py):
it cannot enter an object or a wall. A substep that would push it in is cut short at contact,
the body's velocity drops to zero, and the state's `blocked_by` says what stopped it ("the red
ball 0.35 m ahead"), so the motion skills' stall check fails with that name. A 360-beam range
scan (`get_scan`) comes from the same ray casting as the camera.

Clock: with time_scale 0 simulated time advances only when the controller sleeps, as fast
as the CPU allows. With time_scale s > 0 each simulated second takes s real seconds (or longer,
when the controller or the CPU cannot keep up): while a controller ticks, time passes in its
sleeps only, paced to the wall clock; while nobody ticks, it follows the wall clock.

Long because: it is the Robot protocol's simulated implementation: the clock, the physics, the
postures and the record of what really happened change one state under one lock on every
substep. The world (scene.py), its picture (renderer.py) and the sensors (sensors.py) live
apart.
"""

from __future__ import annotations

import math
import threading
import time
from collections import deque
from dataclasses import dataclass, field, replace
from typing import Any

from ...config import SimConfig
from ...state import CameraFrame, Posture, RobotState, Scan, Sighting, normalize_angle
from ...world import Belief, KnownObject
from ..base import BaseRobot, RobotError
from ..go2 import api as go2_api
from . import renderer, scene, sensors

_SUBSTEP = 0.01  # seconds of physics per integration step
_CONTROLLER_GRACE = 0.25  # wall seconds between sleeps that still count as one ticking loop
_MAX_LAG = 0.1  # wall seconds the clock may fall behind its scale before it slows down instead
_MAX_CATCH_UP = 10.0  # simulated seconds one catch-up may integrate (about 10 ms of CPU)
_PATH_SPACING = 0.01  # metres between recorded ground-truth path points

_POSTURE_SECONDS = {
    (Posture.SITTING, Posture.STANDING): 1.0,
    (Posture.STANDING, Posture.SITTING): 1.0,
    (Posture.LYING, Posture.STANDING): 1.5,
    (Posture.STANDING, Posture.LYING): 1.5,
}


@dataclass(frozen=True)
class RobotCommand:
    """One command the robot received, as recorded by the simulator."""

    stamp: float
    kind: str  # velocity | stop | posture | trick | say
    value: Any
    accepted: bool = True
    note: str = ""


@dataclass
class _Counters:
    motion_commands: int = 0  # accepted non-zero velocity commands
    ignored_motion: int = 0
    tricks: int = 0
    postures: int = 0
    stops: int = 0
    by_kind: dict[str, int] = field(default_factory=dict)


class SimRobot(BaseRobot):
    """A simulated Go2. `SimRobot()` starts standing at the origin with a full battery.

    From BaseRobot it takes: no e-stop source of its own, no navigation server (it walks with
    the project's own planner; `shadowhound sim-driver` serves navigate_to_pose over ROS),
    no bearings (its camera places everything it labels) and nothing to wait for in `look`
    (its camera labels every frame)."""

    def __init__(
        self,
        config: SimConfig | None = None,
        *,
        time_scale: float | None = None,
        world: Any = None,
        map_world: Any = None,
        name: str = "sim-go2",
    ) -> None:
        self.config = config or SimConfig()
        if time_scale is not None:
            self.config = self.config.model_copy(update={"time_scale": float(time_scale)})
        if self.config.time_scale < 0 or not math.isfinite(self.config.time_scale):
            raise ValueError("time_scale must be a finite number >= 0 (0 = as fast as possible)")
        self.name = name
        self.description = "simulated Go2"
        self.tricks = go2_api.offered(ai_mode=True)
        self._world = world
        self.world: scene.World = world if world is not None else scene.DEFAULT_WORLD
        # What the robot's map was made of: the scene itself, or an older one (a stale map).
        self.map_world: scene.World = map_world if map_world is not None else self.world
        self._lock = threading.RLock()
        self._wake = threading.Event()
        self._state = RobotState()
        self._cmd = (0.0, 0.0, 0.0)
        self._sim_time = 0.0
        # Scaled clock: simulated time _anchor[1] was due at wall time _anchor[0]; _ticked is
        # when a controller last read the clock or returned from sleep().
        self._anchor = (time.monotonic(), 0.0)
        self._ticked = -math.inf
        self._commands: deque[RobotCommand] = deque(maxlen=self.config.command_log_size)
        self._counters = _Counters()
        self._closed = False
        # Ground truth, kept apart from what get_state reports, for tests and evaluation.
        self._true_path: deque[tuple[float, float, float]] = deque(
            [(0.0, 0.0, 0.0)], maxlen=self.config.true_path_size
        )
        self._true_path_dropped = 0
        self._true_odometer = 0.0
        self._depth = 0.0  # how far the body overlaps the scene (0 unless reset into it)
        self._belief: Belief | None = None  # the scene's map, built on first use
        self._spoken: deque[str] = deque(maxlen=100)

    # -- clock ---------------------------------------------------------------------------

    @property
    def time_scale(self) -> float:
        return self.config.time_scale

    @property
    def realtime(self) -> bool:
        """At time scale 0 the clock moves only when the controller sleeps."""
        return self.config.time_scale > 0

    def now(self) -> float:
        """Simulated seconds. Reading the clock marks a controller at work (only controllers
        read it), so its work until its next sleep takes no simulated time."""
        with self._lock:
            self._catch_up()
            self._ticked = time.monotonic()
            return self._sim_time

    def sleep(self, seconds: float) -> None:
        if seconds <= 0:
            return
        if self.time_scale == 0:
            with self._lock:
                self._advance(seconds)
            return
        with self._lock:
            self._catch_up()
            target = self._sim_time + seconds
            deadline = self._anchor[0] + (target - self._anchor[1]) * self.time_scale
        # Wait on an event so stop() from another thread wakes the loop early.
        self._wake.clear()
        woken = self._wake.wait(max(0.0, deadline - time.monotonic()))
        with self._lock:
            wall = time.monotonic()
            reach = min(target, self._wall_sim(wall)) if woken else target
            if reach > self._sim_time:
                self._advance(reach - self._sim_time)
            if wall > deadline + _MAX_LAG:  # slower than the scale: run as fast as we can
                self._anchor = (wall, self._sim_time)
            self._ticked = wall

    def _wall_sim(self, wall: float) -> float:
        """The simulated time the wall clock asks for at `wall`, at this time scale."""
        return self._anchor[1] + (wall - self._anchor[0]) / self.time_scale

    def _catch_up(self) -> None:
        """Let simulated time follow the wall clock, unless a controller is ticking: then its
        work between sleeps takes no simulated time (at a time scale of 0.001 a millisecond of
        Python would be a whole simulated second), and time passes only in its sleeps. A
        controller that leaves the clock alone for longer than _CONTROLLER_GRACE (hung, done) hands
        the clock back to the wall, counting the whole gap, so a hung loop's robot walks on
        (up to _MAX_CATCH_UP at once, so a tiny time scale cannot outrun the CPU)."""
        if self.time_scale <= 0:
            return
        wall = time.monotonic()
        if wall - self._ticked <= _CONTROLLER_GRACE:
            return
        behind = self._wall_sim(wall) - self._sim_time
        if behind > _MAX_CATCH_UP:  # more than the CPU can simulate at once: drop the rest
            self._advance(_MAX_CATCH_UP)
            self._anchor = (wall, self._sim_time)
        elif behind > 0:
            self._advance(behind)

    # -- physics -------------------------------------------------------------------------

    def _advance(self, seconds: float) -> None:
        remaining = seconds
        while remaining > 1e-12:
            dt = min(_SUBSTEP, remaining)
            self._integrate(dt)
            remaining -= dt

    def _integrate(self, dt: float) -> None:
        cfg = self.config
        s = self._state
        standing = s.posture is Posture.STANDING and not s.estopped
        tx, ty, tw = self._cmd if standing else (0.0, 0.0, 0.0)
        vx = _approach(s.vx, tx, cfg.linear_accel * dt)
        vy = _approach(s.vy, ty, cfg.linear_accel * dt)
        wz = _approach(s.wz, tw, cfg.angular_accel * dt)
        # Integrate with the mean velocity over the substep, heading at the midpoint.
        mvx, mvy, mwz = (s.vx + vx) / 2, (s.vy + vy) / 2, (s.wz + wz) / 2
        mid_yaw = s.yaw + mwz * dt / 2
        c, si = math.cos(mid_yaw), math.sin(mid_yaw)
        dx = (mvx * c - mvy * si) * dt
        dy = (mvx * si + mvy * c) * dt
        blocked_by = s.blocked_by if not (dx or dy) else ""
        depth, what = (
            sensors.penetration(self.world, s.x + dx, s.y + dy, cfg.body_radius)
            if cfg.collisions
            else (0.0, "")
        )
        if depth > self._depth + 1e-12:
            # Cut the substep short at contact: the largest fraction that goes no deeper.
            lo, hi = 0.0, 1.0
            for _ in range(30):
                mid = (lo + hi) / 2
                d, _ = sensors.penetration(
                    self.world, s.x + dx * mid, s.y + dy * mid, cfg.body_radius
                )
                lo, hi = (mid, hi) if d <= self._depth + 1e-12 else (lo, mid)
            dx, dy = dx * lo, dy * lo
            vx = vy = 0.0
            blocked_by = self._describe_block(s.x + dx, s.y + dy, mid_yaw, what)
        else:
            self._depth = depth
        step = math.hypot(dx, dy)
        drain = cfg.battery_drain_idle * dt + cfg.battery_drain_per_metre * step
        self._state = replace(
            s,
            x=s.x + dx,
            y=s.y + dy,
            yaw=normalize_angle(s.yaw + mwz * dt),
            vx=vx,
            vy=vy,
            wz=wz,
            battery=max(0.0, (s.battery or 0.0) - drain),  # the simulator always knows it
            distance_travelled=s.distance_travelled + step,
            angle_turned=s.angle_turned + abs(mwz * dt),
            time_moving=s.time_moving + (dt if step > 0 or mwz else 0.0),
            stamp=self._sim_time + dt,
            blocked_by=blocked_by,
        )
        self._sim_time += dt
        self._true_odometer += step
        _t, last_x, last_y = self._true_path[-1]
        if math.hypot(s.x + dx - last_x, s.y + dy - last_y) >= _PATH_SPACING:
            self._note_true_point()

    def _describe_block(self, x: float, y: float, yaw: float, what: str) -> str:
        """ "the red ball 0.35 m ahead": the blocker, its surface's distance and side."""
        radius = self.config.body_radius
        depth, _ = sensors.penetration(self.world, x, y, radius)
        obj = self.world.find(what[4:]) if what != "the wall" else None
        if obj is not None:
            bearing = math.atan2(obj.y - y, obj.x - x)
        else:  # the nearest wall is the one the body presses on
            x_min, x_max, y_min, y_max = self.world.bounds
            gaps = {
                0.0: x_max - x,
                math.pi: x - x_min,
                math.pi / 2: y_max - y,
                -math.pi / 2: y - y_min,
            }
            bearing = min(gaps, key=lambda a: gaps[a])
        side = normalize_angle(bearing - yaw)
        where = (
            "ahead"
            if abs(side) <= math.pi / 4
            else "behind"
            if abs(side) >= 3 * math.pi / 4
            else "to the left"
            if side > 0
            else "to the right"
        )
        return f"{what} {max(0.0, radius - depth):.2f} m {where}"

    # -- Robot protocol ------------------------------------------------------------------

    def get_state(self) -> RobotState:
        with self._lock:
            self._catch_up()
            return replace(self._state, stamp=self._sim_time)

    def last_state(self) -> RobotState:
        """The simulator always knows its state."""
        return self.get_state()

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        values = (float(vx), float(vy), float(wz))
        if not all(math.isfinite(v) for v in values):
            raise RobotError(f"velocity must be finite numbers, got {values}")
        cfg = self.config
        clamped = (
            _clamp(values[0], cfg.max_linear_speed),
            _clamp(values[1], cfg.max_linear_speed),
            _clamp(values[2], cfg.max_angular_speed),
        )
        with self._lock:
            self._catch_up()
            posture = self._state.posture
            accepted = posture is Posture.STANDING and not self._state.estopped
            note = "" if accepted else f"ignored: robot is {posture.value}"
            if self._state.estopped:
                note = "ignored: e-stop latched"
            self._record("velocity", clamped, accepted, note)
            if accepted:
                self._cmd = clamped
                if any(clamped):
                    self._counters.motion_commands += 1
            else:
                self._counters.ignored_motion += int(any(clamped))

    def stop(self) -> None:
        with self._lock:
            self._catch_up()
            self._cmd = (0.0, 0.0, 0.0)
            self._counters.stops += 1
            self._record("stop", None, True)
        self._wake.set()

    def emergency_stop(self) -> None:
        """Hard stop: velocity to zero at once and further motion ignored until released."""
        with self._lock:
            self._catch_up()
            self._cmd = (0.0, 0.0, 0.0)
            self._state = replace(self._state, vx=0.0, vy=0.0, wz=0.0, estopped=True)
            self._record("estop", None, True)
        self._wake.set()

    def release_estop(self) -> None:
        with self._lock:
            self._state = replace(self._state, estopped=False)
            self._record("estop_release", None, True)

    def vocabulary(self) -> frozenset[str]:
        """What its camera can label: the names of the objects of its world."""
        return frozenset(o.name for o in self.world.objects)

    def set_posture(self, posture: Posture, seconds: float | None = None) -> None:
        """Change posture, taking the Go2's typical time (or `seconds` for the whole change)."""
        posture = Posture(posture)
        with self._lock:
            self._catch_up()
            current = self._state.posture
            if self._state.estopped:
                self._record("posture", posture.value, False, "ignored: e-stop latched")
                raise RobotError("e-stop is latched; release it before changing posture")
            self._record("posture", posture.value, True)
            self._counters.postures += 1
            self._cmd = (0.0, 0.0, 0.0)
        if current is posture:
            return
        path = [current, posture]
        if Posture.STANDING not in path:  # sitting <-> lying goes through standing
            path = [current, Posture.STANDING, posture]
        for a, b in zip(path, path[1:], strict=False):
            self._settle()
            self.sleep(_POSTURE_SECONDS[(a, b)] if seconds is None else seconds / (len(path) - 1))
            with self._lock:
                self._state = replace(self._state, posture=b)

    def perform(self, trick: str) -> None:
        info = self.tricks.get(trick)
        with self._lock:
            self._catch_up()
            if info is None:
                self._record("trick", trick, False, "unknown trick")
                raise RobotError(f"unknown trick {trick!r}; known: {', '.join(self.tricks)}")
            if self._state.estopped or self._state.posture is not Posture.STANDING:
                why = "e-stop latched" if self._state.estopped else self._state.posture.value
                self._record("trick", trick, False, f"ignored: {why}")
                raise RobotError(f"cannot perform {trick} while {why}; stand up first")
            self._record("trick", trick, True)
            self._counters.tricks += 1
            self._cmd = (0.0, 0.0, 0.0)
        self.sleep(info.duration)

    def say(self, text: str) -> None:
        """The simulator's speaker is its record: `spoken` (and the command log) keep the words;
        the agent's `Spoken` event shows them on dashboards."""
        with self._lock:
            self._record("say", text, True)
            self._spoken.append(text)

    @property
    def spoken(self) -> list[str]:
        """What the robot said aloud, oldest first (the last 100 sayings)."""
        with self._lock:
            return list(self._spoken)

    def get_camera_frame(self) -> CameraFrame | None:
        state = self.get_state()
        return renderer.camera_frame(
            self.world,
            state.pose,
            width=self.config.camera_width,
            height=self.config.camera_height,
        )

    def in_view(self) -> tuple[Sighting, ...]:
        """What its camera labels in view now (the scene's truth, as the frame would), without
        rendering the picture."""
        return scene.visible_objects(self.world, self.get_state().pose)  # as camera_frame

    def set_battery(self, percent: float) -> None:
        """Set the battery's charge (0 to 100 percent): a low battery to test against. It
        drains from there as before."""
        level = float(percent)
        if not (math.isfinite(level) and 0.0 <= level <= 100.0):
            raise ValueError(f"battery must be a percent from 0 to 100, got {percent!r}")
        with self._lock:
            self._catch_up()
            self._state = replace(self._state, battery=level)

    def set_world(self, world: scene.World) -> None:
        """Change the scene while it runs (a person steps into the path): the body, the scan
        and the camera meet the new one from now on; the map the robot was told stays."""
        with self._lock:
            self._catch_up()
            self.world = world

    def get_scan(self) -> Scan | None:
        """A 360-beam range scan (0.1 to 8 m) from the robot's true pose, on the sim clock."""
        state = self.get_state()
        return sensors.cast_scan(self.world, state.pose, stamp=state.stamp)

    def known_objects(self) -> tuple[KnownObject, ...]:
        """What the robot has seen (its belief's objects)."""
        belief = self.belief()
        return belief.objects if belief is not None else ()

    def belief(self) -> Belief | None:
        """The robot's world model: the scene's map (labelled with the scene's object names,
        to say what is in the way) and the objects it has seen (`Belief.sight`, none at
        first). One object for the robot's life, so scan updates and sightings of one mission
        are known to the next. None with collisions off: then the scene is not physical, and
        nothing in it is in the way."""
        if not self.config.collisions:
            return None
        if self._belief is None:
            told = sensors.scene_belief(self.map_world, self.config.body_radius)
            self._belief = Belief(told.grid, (), told.robot_radius, told.room, labels=told.objects)
        return self._belief

    def close(self) -> None:
        self.stop()
        self._closed = True

    # -- inspection (for tests, eval and dashboards) --------------------------------------

    @property
    def commands(self) -> list[RobotCommand]:
        """Every command received (bounded by SimConfig.command_log_size), oldest first."""
        with self._lock:
            return list(self._commands)

    @property
    def received_motion(self) -> bool:
        """True when any non-zero velocity command was accepted (the robot was asked to move)."""
        return self._counters.motion_commands > 0

    @property
    def counters(self) -> dict[str, int]:
        with self._lock:
            c = self._counters
            return {
                "motion_commands": c.motion_commands,
                "ignored_motion": c.ignored_motion,
                "tricks": c.tricks,
                "postures": c.postures,
                "stops": c.stops,
                **c.by_kind,
            }

    @property
    def true_path(self) -> list[tuple[float, float, float]]:
        """Where the body really was: (sim time, x, y), oldest first, points about 1 cm apart
        while it moves, ending where it is now. Starts again at a `reset`; check
        `true_path_complete` before relying on the oldest points."""
        with self._lock:
            self._catch_up()
            s = self._state
            return [*self._true_path, (self._sim_time, s.x, s.y)]

    @property
    def true_path_complete(self) -> bool:
        """False when more points were recorded than SimConfig.true_path_size keeps."""
        with self._lock:
            return self._true_path_dropped == 0

    @property
    def true_odometer(self) -> float:
        """Metres the body really walked since the simulator started (resets do not walk)."""
        with self._lock:
            self._catch_up()
            return self._true_odometer

    def reset(self, x: float = 0.0, y: float = 0.0, yaw: float = 0.0) -> None:
        """Put the robot back at a pose, standing, stopped, with a full battery."""
        with self._lock:
            self._cmd = (0.0, 0.0, 0.0)
            self._state = RobotState(x=x, y=y, yaw=normalize_angle(yaw), stamp=self._sim_time)
            self._true_path.clear()
            self._true_path_dropped = 0
            self._note_true_point()
            self._depth = max(
                0.0, sensors.penetration(self.world, x, y, self.config.body_radius)[0]
            )

    def _settle(self) -> None:
        """Let the body come to rest (bounded) before a posture change."""
        for _ in range(200):
            if not self.get_state().is_moving:
                return
            self.sleep(_SUBSTEP * 5)

    def _note_true_point(self) -> None:
        if len(self._true_path) == self._true_path.maxlen:
            self._true_path_dropped += 1
        self._true_path.append((self._sim_time, self._state.x, self._state.y))

    def _record(self, kind: str, value: Any, accepted: bool, note: str = "") -> None:
        self._commands.append(RobotCommand(self._sim_time, kind, value, accepted, note))
        self._counters.by_kind[kind] = self._counters.by_kind.get(kind, 0) + 1


MockRobot = SimRobot
"""Alias kept from the original ShadowHound design: the simulator is the development robot."""


def _approach(current: float, target: float, max_delta: float) -> float:
    if target > current:
        return min(target, current + max_delta)
    return max(target, current - max_delta)


def _clamp(value: float, limit: float) -> float:
    return max(-limit, min(limit, value))
