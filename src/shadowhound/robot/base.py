"""The `Robot` protocol: the small surface every robot (simulated or real) implements.

Skills drive robots only through this protocol. Motion is commanded as body-frame velocity
and closed on the measured pose (`get_state`), so the same skill code runs on the simulator
and on a Go2 through ROS 2. Everything the agent, the skills and the interfaces use of a robot
is declared here, so nobody probes a robot for what it can do.
"""

from __future__ import annotations

from collections.abc import Callable
from typing import TYPE_CHECKING, Protocol, runtime_checkable

from ..errors import RobotError as RobotError
from ..state import CameraFrame, Posture, RobotState, Scan
from .navigator import Navigator

if TYPE_CHECKING:
    from ..world import Belief, KnownObject
    from ..world.image_sighting import Bearing


@runtime_checkable
class Robot(Protocol):
    """A quadruped the agent can drive. Implementations must make `stop` thread-safe."""

    name: str
    # What the robot is and how it is reached, in a person's words ("simulated Go2", "Go2
    # over ROS (namespace /robot0)"): dashboards say which robot they drive.
    description: str

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

    def get_state(self) -> RobotState:
        """The latest state (pose from odometry, posture, battery). Raises RobotError when the
        robot cannot say (e.g. no odometry yet)."""
        ...

    def last_state(self) -> RobotState:
        """The last known state without raising (`connected` False when it is stale)."""
        ...

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        """Command body-frame velocity (m/s, m/s, rad/s). Ignored unless standing."""
        ...

    def stop(self) -> None:
        """Zero velocity now. Safe to call from any thread, at any time."""
        ...

    def emergency_stop(self) -> None:
        """Stop now and refuse motion and postures until `release_estop`. Thread-safe."""
        ...

    def release_estop(self) -> None:
        """Accept commands again after `emergency_stop`."""
        ...

    def watch_estop(self, listener: Callable[[bool], None]) -> None:
        """Call `listener(True)` when the robot's own e-stop source (a ROS topic it listens
        on, a button) stopped it and latched, `listener(False)` when a person released it
        there. The agent latches and releases with it. A robot without one never calls."""
        ...

    def set_posture(self, posture: Posture) -> None:
        """Stand, sit or lie down; returns when the transition is done. Raises RobotError."""
        ...

    def perform(self, trick: str) -> None:
        """Run a sport-mode trick by name (see go2_api.TRICKS); returns when done."""
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
