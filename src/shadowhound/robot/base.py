"""The `Robot` protocol: the small surface every robot (simulated or real) implements.

Skills drive robots only through this protocol. Motion is commanded as body-frame velocity
and closed on the measured pose (`get_state`), so the same skill code runs on the simulator
and on a Go2 through ROS 2. Everything the agent, the skills and the interfaces use of a robot
is declared here, so nobody probes a robot for what it can do.

`BaseRobot` is the protocol with sensible defaults (a wall clock, no sensors, no map, no
navigator, no voice, no tricks, no e-stop source of its own): a new backend inherits it and
writes only what it has. tests/robot/test_contract.py holds every backend to the contract the
docstrings below state.
"""

from __future__ import annotations

import time
from abc import ABC, abstractmethod
from collections.abc import Callable, Mapping
from types import MappingProxyType
from typing import TYPE_CHECKING, NamedTuple, Protocol, runtime_checkable

from ..errors import RobotError as RobotError
from ..state import CameraFrame, Posture, RobotState, Scan, Sighting
from .navigator import Navigator

if TYPE_CHECKING:
    from ..world import Belief, KnownObject
    from ..world.image_sighting import Bearing


class TrickInfo(Protocol):
    """A trick a robot performs in place (a Go2's sport-mode "hello", "dance1"): what the
    `body.sport` skill offers and the safety layer weighs."""

    @property
    def name(self) -> str: ...

    @property
    def description(self) -> str: ...

    @property
    def duration(self) -> float:
        """Seconds the robot is busy with it."""
        ...

    @property
    def risky(self) -> bool:
        """It can hurt people or the robot: it needs a person's explicit approval."""
        ...


NO_TRICKS: Mapping[str, TrickInfo] = MappingProxyType({})
# Seconds: the longest stall of a robot's link (`Robot.stalls`) allowed for between what was
# commanded and what odometry shows, as seen on loaded 2-core machines; no more is.
MAX_STALL = 0.5


class Stall(NamedTuple):
    """A stretch of robot time (`start` to `end`) in which the link to the robot was seen
    stalled: a command sent in it may have acted only at its end."""

    start: float
    end: float

    @property
    def seconds(self) -> float:
        return self.end - self.start


@runtime_checkable
class Robot(Protocol):
    """A quadruped the agent can drive. Implementations must make `stop` thread-safe."""

    name: str
    # What the robot is and how it is reached, in a person's words ("simulated Go2", "Go2
    # over ROS (namespace /robot0)"): dashboards say which robot they drive.
    description: str
    # The tricks it performs, by name (`perform`); empty: none, and no `body.sport` skill is
    # offered. robot.factory.tricks_of says the same of a backend before it is built.
    tricks: Mapping[str, TrickInfo]

    @property
    def time_scale(self) -> float:
        """Real seconds per robot second: 1 for a real robot, 0 for a simulator that runs as
        fast as it can (its clock only moves when the control loop sleeps)."""
        ...

    @property
    def latency(self) -> float:
        """Seconds its measured pose may lag its motion (0: it knows its pose at once): steps
        allow for it in their waits for rest and their time-outs."""
        ...

    @property
    def realtime(self) -> bool:
        """True when the robot's clock runs by itself (a hung skill then needs a watchdog)."""
        ...

    def stalls(self, since: float) -> tuple[Stall, ...]:
        """The stalls of the link to the robot seen since `since` (robot clock), oldest first:
        a pose that came in later than it was sent (from when it was sent to when it came in),
        or a pause in what it sends beyond its usual rate (a loaded machine, a late link). A
        command sent in one may have acted only at its end, so a step allows for them between
        its commands and its pose. None for a robot whose pose is known at once."""
        ...

    def get_state(self) -> RobotState:
        """The latest state (pose from odometry, posture, battery). Raises RobotError when the
        robot is blind where it matters: its odometry went stale while motion is under way
        (velocity commanded since the last `stop`), or it does not trust its odometry. At rest
        a robot that has lost its odometry returns its last state with `connected` False, so
        reports and plans still work; one that cannot lose it (the simulator) never raises."""
        ...

    def last_state(self) -> RobotState:
        """The last known state without raising (`connected` False when it is stale)."""
        ...

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        """Command body-frame velocity (m/s, m/s, rad/s). Ignored, without an error, while
        the robot is not standing or the e-stop is latched: the robot does not move, and the
        command is not kept for later (standing up or a release does not start a walk).
        Raises RobotError for values that are not finite, and when the robot is blind (it
        refuses to start moving without odometry)."""
        ...

    def stop(self) -> None:
        """Zero velocity now; the robot comes to rest. Safe to call from any thread, at any
        time, any number of times, also from many threads at once."""
        ...

    def emergency_stop(self) -> None:
        """Stop now and latch (`get_state().estopped`) until `release_estop`: meanwhile
        velocity is ignored (as `send_velocity` says) and `set_posture` and `perform` raise
        RobotError. Thread-safe."""
        ...

    def release_estop(self) -> None:
        """Accept commands again after `emergency_stop`. The robot stays at rest until it is
        commanded again."""
        ...

    def watch_estop(self, listener: Callable[[bool], None]) -> None:
        """Call `listener(True)` when the robot's own e-stop source (a ROS topic it listens
        on, a button) stopped it and latched, `listener(False)` when a person released it
        there. The agent latches and releases with it. A robot without one never calls."""
        ...

    def set_posture(self, posture: Posture) -> None:
        """Stand, sit or lie down; returns when the transition is done (`get_state().posture`
        shows it). Raises RobotError when it cannot, or while the e-stop is latched."""
        ...

    def perform(self, trick: str) -> None:
        """Run one of its `tricks` by name; returns when done. Raises RobotError for a trick it
        does not offer, while not standing or while the e-stop is latched."""
        ...

    def say(self, text: str) -> None:
        """Speak `text` (cleaned and cut by `speech.Voice`) through the robot's speaker and
        return at once, before it is heard: speaking never holds up motion. Raises RobotError
        when the robot has no voice."""
        ...

    def now(self) -> float:
        """Seconds on the robot's clock (simulated or wall)."""
        ...

    def sleep(self, seconds: float) -> None:
        """Let `seconds` of robot time pass (the control loop's tick)."""
        ...

    def get_camera_frame(self) -> CameraFrame | None:
        """The robot's own latest camera frame, if it has a camera."""
        ...

    def get_scan(self) -> Scan | None:
        """The latest planar range scan, or None for a robot without a range sensor."""
        ...

    def belief(self) -> Belief | None:
        """The robot's world model: its map and the objects it knows (one object for the
        robot's life, updated in place by scans, map messages and sightings), or None when
        it has no map."""
        ...

    def known_objects(self) -> tuple[KnownObject, ...]:
        """Every object the robot knows, one per name (the latest sighting): its world model's,
        and those it was told of without a map (a detector on ROS)."""
        ...

    def bearings(self) -> tuple[Bearing, ...]:
        """What it saw in a direction only, at no usable distance (a 2-D detector's box with no
        scan return in it, or beyond its range), the latest last: hints a search names when it
        ends without the thing, never a place to go. Empty when all it sees is placed."""
        ...

    def in_view(self) -> tuple[Sighting, ...] | None:
        """What its camera or detector labels in view now (name, distance, bearing), cheap
        enough to read every control tick (a step's watches read it), nearest first. None
        when it cannot tell what is in view now: then nothing can be watched for by sight."""
        ...

    def look(self) -> None:
        """Let what the robot recognises catch up with its view now (a detector runs at its
        own rate, behind the camera): returns once it has reported on this view, or after a
        bound. Immediate for a camera that labels each frame (the simulator)."""
        ...

    def vocabulary(self) -> frozenset[str] | None:
        """The names of the kinds of thing its camera or detector can recognise ("red ball",
        "chair"): a search may look only for these. None when its detector reports names not
        known in advance (any name may be looked for); empty when it recognises nothing."""
        ...

    def navigator(self) -> Navigator | None:
        """The robot's navigation server (Nav2's NavigateToPose), or None when it has none."""
        ...

    def close(self) -> None:
        """Stop and release resources."""
        ...


class BaseRobot(ABC):
    """The `Robot` protocol with defaults for what a robot may lack: a backend inherits it and
    writes only what it has. A robot is, unless it says otherwise: on the wall clock
    (`time_scale` 1, `realtime`), knowing its pose at once (`latency` 0, no `stalls`),
    blind to its surroundings (no camera frame, no scan, no map, no objects, no bearings,
    recognising nothing), without a navigation server, a voice, tricks or an e-stop source of
    its own. Closing it stops it.

    What every robot must say for itself is abstract: its name, its state, velocity, stops,
    the e-stop latch and postures."""

    name: str
    description: str
    tricks: Mapping[str, TrickInfo] = NO_TRICKS

    @property
    def time_scale(self) -> float:
        return 1.0

    @property
    def latency(self) -> float:
        return 0.0

    @property
    def realtime(self) -> bool:
        return True

    def stalls(self, since: float) -> tuple[Stall, ...]:
        return ()

    @abstractmethod
    def get_state(self) -> RobotState: ...

    @abstractmethod
    def last_state(self) -> RobotState: ...

    @abstractmethod
    def send_velocity(self, vx: float, vy: float, wz: float) -> None: ...

    @abstractmethod
    def stop(self) -> None: ...

    @abstractmethod
    def emergency_stop(self) -> None: ...

    @abstractmethod
    def release_estop(self) -> None: ...

    def watch_estop(self, listener: Callable[[bool], None]) -> None:  # noqa: B027 (a default)
        """No e-stop source of its own: `listener` is never called."""

    @abstractmethod
    def set_posture(self, posture: Posture) -> None: ...

    def perform(self, trick: str) -> None:
        """No tricks: every one is refused."""
        raise RobotError(f"{self.description} performs no tricks (asked for {trick!r})")

    def say(self, text: str) -> None:
        """No voice."""
        raise RobotError(f"{self.description} has no voice")

    def now(self) -> float:
        """The wall clock (monotonic seconds)."""
        return time.monotonic()

    def sleep(self, seconds: float) -> None:
        if seconds > 0:
            time.sleep(seconds)

    def get_camera_frame(self) -> CameraFrame | None:
        return None

    def get_scan(self) -> Scan | None:
        return None

    def belief(self) -> Belief | None:
        return None

    def known_objects(self) -> tuple[KnownObject, ...]:
        return ()

    def bearings(self) -> tuple[Bearing, ...]:
        return ()

    def in_view(self) -> tuple[Sighting, ...] | None:
        """It cannot tell what is in view."""
        return None

    def look(self) -> None:  # noqa: B027 (a default: nothing to do)
        """Nothing to wait for: no detector runs behind its camera."""

    def vocabulary(self) -> frozenset[str] | None:
        """It recognises nothing."""
        return frozenset()

    def navigator(self) -> Navigator | None:
        return None

    def close(self) -> None:
        self.stop()
