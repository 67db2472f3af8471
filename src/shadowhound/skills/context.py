"""What a running skill can use: the robot, the limits, the clock, cancellation and the camera.

Long because: SkillContext is the one door every skill drives the robot through; its checks,
the ledger of its commands, the stalls it has seen, its waits for odometry and the watchdog's
heartbeat share one state (what was last commanded, and since when), which a split would
hand back and forth.
"""

from __future__ import annotations

import math
import threading
from collections.abc import Callable, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING

from ..budget import MissionBudget, out_of_time, walked_too_far
from ..config import ShadowHoundConfig
from ..errors import MissionCancelled, PlanProblem, RobotError, SkillError, SkillTimeout
from ..memory.records import Secondhand
from ..memory.service import AgentMemory
from ..plan import Watch
from ..robot.base import Robot, Stall
from ..speech import Saying
from ..state import CameraFrame, Pose2D, Posture, RobotState
from ..world import Belief, KnownObject
from .bounds import MAX_STALL, CommandLedger, Leeway, fences, room_ahead, room_on_map
from .watches import Watcher, raise_if_fired

if TYPE_CHECKING:
    from ..watchdog import Trip

_TRANSLATING = 0.05  # m/s commanded: the robot goes somewhere (a path check looks along it)
# Robot seconds a step stopped for stale odometry waits, at rest, for it to come back: a loaded
# machine stalls the stream (this process, the driver) for a fraction of a second.
ODOMETRY_RETURN = 2.0


@dataclass
class PlanEnv:
    """What predictions and checks know about one mission.

    `places` are the named places of this mission: the profile's, then taught ones. Skills that
    teach or forget a place update it, so later steps of the same plan see the change.
    `budget` is what the mission has used of its limits so far (the agent sets it once per
    mission; None checks a plan on its own, as if the mission had just begun).
    `belief` is the robot's map and known objects (None: no map, so paths are straight lines
    and nothing is known to be in the way). nav.goto updates its grid from scans when blocked.
    """

    config: ShadowHoundConfig
    mission_start: Pose2D = field(default_factory=Pose2D)
    places: dict[str, tuple[float, float]] = field(default_factory=dict)
    budget: MissionBudget | None = None
    belief: Belief | None = None
    # Names nav.goto looked for during this mission: their approach was not predictable.
    searched: set[str] = field(default_factory=set)
    # What the robot can recognise (`Robot.vocabulary`): a search may look only for these
    # (None: any name, its detector's names are not known in advance).
    vocabulary: frozenset[str] | None = None
    # Places and sightings in memory that are not this robot's (`AgentMemory.secondhand`):
    # never goals; an answer about one of their names says whose they are.
    secondhand: tuple[Secondhand, ...] = ()

    def __post_init__(self) -> None:
        self.places = {**self.config.places, **self.places}

    def resolve_place(self, name: str) -> tuple[float, float]:
        key = " ".join(name.strip().lower().split())
        if key.startswith("the "):
            key = key[4:]
        if key in self.places:
            return self.places[key]
        if key in ("start", "mission start", "where i started", "starting point"):
            return (self.mission_start.x, self.mission_start.y)
        if key in ("home", "origin"):
            return (0.0, 0.0)
        known = ", ".join([*self.places, "start", "home"])
        raise PlanProblem(f"unknown place {name!r}; known places: {known}")


def robot_belief(robot: Robot) -> Belief | None:
    """The map a robot offers (`Robot.belief`: the simulator's scene), or None when it has none."""
    return robot.belief()


def robot_objects(robot: Robot) -> tuple[KnownObject, ...]:
    """Every object the robot knows (`Robot.known_objects`: its world model's and, on ROS, its
    detections'), the latest sighting per name."""
    return robot.known_objects()


class SkillContext:
    """Handed to every running skill. `tick()` is the control loop's heartbeat."""

    def __init__(
        self,
        robot: Robot,
        env: PlanEnv,
        cancelled: threading.Event,
        *,
        camera: Callable[[], CameraFrame | None] = lambda: None,
        vision: Callable[[CameraFrame, str], str] | None = None,
        on_progress: Callable[[float], None] = lambda _fraction: None,
        heartbeat: Callable[[bool | None], Trip | None] = lambda _moving: None,
        memory: AgentMemory | None = None,
        say: Callable[[str], Saying] | None = None,
        answer: Callable[[], str | None] = lambda: None,
    ) -> None:
        self.robot = robot
        self.env = env
        self.config = env.config
        self._cancelled = cancelled
        self._camera = camera
        self.vision = vision
        self.on_progress = on_progress
        self.heartbeat = heartbeat
        self.memory = memory  # AgentMemory: places, recall
        self._say = say
        # The mission's latest answer so far (what a step that reports said), None before one.
        self.answer = answer
        self.period = 1.0 / self.config.motion.control_rate_hz
        self._last_command = (0.0, 0.0, 0.0)
        self.deadline = math.inf
        self._late = ""
        self.notes: list[str] = []
        self.ledger: CommandLedger | None = None  # the step's commands, from its first one
        self._leg_began = -math.inf  # robot time the current leg began (stalls count from it)
        self._ticked: float | None = None  # robot time the last tick of this leg ended
        self._late_ticks: list[Stall] = []  # this leg's ticks that came late: its own stalls
        self._needs: Posture | None = None  # the posture the step runs in (ensure_standing)
        self._start_clearance: list[float] | None = None  # per fence, where the step began
        self._watcher: Watcher | None = None  # the step's watches (`watch`)

    def watch(self, watches: Sequence[Watch]) -> None:
        """Check `watches` at every `check` from now on: the first that holds stops the robot
        and raises WatchFired (plan.Watch says what each means)."""
        if watches:
            self._watcher = Watcher(watches, self.robot, self.config.sim.body_radius)

    def start_clock(self, timeout: float) -> None:
        """Give the skill `timeout` seconds of robot time, more on a robot whose pose lags
        (each approach waits for it to show the robot at rest), never past the mission's end."""
        timeout += 4 * self.robot.latency  # the first approach and up to three corrections
        self.deadline = self.robot.now() + timeout
        self._late = f"timed out after {timeout:.1f} s (robot clock)"
        budget, limit = self.env.budget, self.config.safety.max_mission_duration
        if budget is not None and budget.deadline(limit) < self.deadline:
            self.deadline, self._late = budget.deadline(limit), out_of_time(limit)

    def check(self) -> RobotState:
        """Raise if the mission was cancelled, the skill ran out of time, the robot cannot
        say where it is (`get_state` raises RobotError: stale or untrusted odometry), it left
        the posture the step runs in, a walking step's body (measured, or where the step's
        commands put it) is outside a geofence, or it walked past the mission's distance
        (whatever the plan predicted: a detour, a skill that predicts no path), with
        `outcome_tolerance` of slack for control error. Returns the state it read."""
        if self._cancelled.is_set():
            raise MissionCancelled("mission cancelled")
        if self.robot.now() > self.deadline:
            raise SkillTimeout(self._late)
        state = self.state()
        if self._watcher is not None:
            vx, vy, _ = self._last_command  # where it goes: a path check looks along it
            heading = math.atan2(vy, vx) if math.hypot(vx, vy) > _TRANSLATING else None
            raise_if_fired(self._watcher, state, heading)
        if self._needs is not None and state.posture is not self._needs:
            self.robot.stop()
            raise SkillError(
                f"the robot is {state.posture.value} now, not {self._needs.value} as the step "
                "needs: it fell, or something else changed its posture; stopped"
            )
        if self._needs is not None:  # a step that walks (it stood up for it)
            self._check_fences(state)
        budget, safety = self.env.budget, self.config.safety
        if budget is not None:
            walked = budget.travelled(state)
            if walked > safety.max_mission_distance + safety.outcome_tolerance:
                raise SkillError(walked_too_far(walked, safety.max_mission_distance))
        return state

    def _check_fences(self, state: RobotState) -> None:
        """The body, where odometry puts it and where the commands put it, stays inside every
        geofence (a step that began within a fence's margin may not come closer to it)."""
        lim = self.config.safety
        slack = max(self.config.motion.position_tolerance, 0.02)
        poses = [("measured", state.pose)]
        if self.ledger is not None:
            self.ledger.advance(self.robot.now())
            poses.append(("commanded", self.ledger.pose))
        all_fences = fences(lim)
        if self._start_clearance is None:
            self._start_clearance = [f.clearance((state.x, state.y)) for f, _n, _w in all_fences]
        for (fence, name, where), start in zip(all_fences, self._start_clearance, strict=True):
            need = max(0.0, min(lim.geofence_margin, start)) - slack
            for which, pose in poses:
                if fence.clearance((pose.x, pose.y)) < need:
                    self.robot.stop()
                    raise SkillError(
                        f"the robot's body would leave {name} {where}: its {which} position "
                        f"({pose.x:.2f}, {pose.y:.2f}) keeps less than "
                        f"{lim.geofence_margin:g} m from the edge; stopped"
                    )

    def room(self, heading: float, reach: float, state: RobotState) -> tuple[float, str]:
        """Metres the robot may still go along `heading` (odom frame), looking `reach` ahead:
        before its body would reach a geofence (from the measured and from the commanded
        pose: the stricter wins) and within the mission's distance. With why it is so small."""
        # A goal may lie on the fence's margin (the plan check allows it): leave the loop
        # enough room to arrive within its tolerance, and barely more.
        lim, slack = self.config.safety, min(self.config.motion.position_tolerance, 0.005)
        room, why = room_ahead(lim, state.pose, heading, reach, slack)
        if self.ledger is not None:
            commanded, fence = room_ahead(lim, self.ledger.pose, heading, reach, slack)
            if commanded < room:
                room, why = commanded, fence
        reasons = {why: f"going on would take the robot's body outside {why}"} if why else {}
        budget = self.env.budget
        if budget is not None:
            left = lim.max_mission_distance - budget.travelled(state)
            if left < room:
                room, why = max(0.0, left), "mission"
                reasons[why] = walked_too_far(budget.travelled(state), lim.max_mission_distance)
        return room, reasons.get(why, "")

    def room_on_path(self, heading: float, reach: float, state: RobotState) -> tuple[float, str]:
        """`room`, and anything on the map in the way, from the measured pose: what is in the
        way of a mission's leg (`bounds.room_on_map`). For motion whose path is not known
        before it runs (nav.follow), which looks along its heading every tick."""
        room, why = self.room(heading, reach, state)
        ahead, what = room_on_map(self.env.belief, state.pose, heading, reach)
        if what and ahead < room:
            return ahead, f"{what} is in the way"
        return room, why

    def state(self) -> RobotState:
        """The robot's state. Odometry gone stale while it moved (this process, the link or
        the driver stalled, or the stream stopped) stops the robot at once; the step then waits
        at rest, up to ODOMETRY_RETURN seconds, for odometry to come back, and fails naming the
        stale stream only if it does not. Odometry that is not trusted fails at once."""
        try:
            return self.robot.get_state()
        except RobotError as blind:
            if self.robot.last_state().connected:
                raise  # not stale: untrusted, and no wait for a lie
            return self._await_odometry(blind)

    def _await_odometry(self, blind: RobotError) -> RobotState:
        self.robot.stop()
        lim = self.config.safety
        if self.ledger is not None:  # it brakes from where it was going, as far as that takes
            walked = self.ledger.halt(self.robot.now(), lim.max_linear_accel, lim.max_angular_accel)
            if self.env.budget is not None:
                self.env.budget.command(walked)
        self._last_command = (0.0, 0.0, 0.0)
        self.heartbeat(False)
        began = self.robot.now()
        while True:
            state = self.robot.get_state()  # raises when odometry is not trusted, at rest too
            if state.connected:
                self._ticked = None  # the wait is no late tick (the stream shows the stall)
                note = (
                    "stopped while odometry paused (a loaded machine or a late link), and went on"
                )
                if note not in self.notes:
                    self.notes.append(note)
                return state
            if self._cancelled.is_set():
                raise MissionCancelled("mission cancelled")
            if self.robot.now() - began > ODOMETRY_RETURN:
                raise RobotError(
                    f"{blind} Stopped; it did not come back within {ODOMETRY_RETURN:g} s"
                )
            self.robot.sleep(self.period)
            self.heartbeat(None)

    def stalls(self) -> list[Stall]:
        """The stalls seen since the current leg began: of the link (`Robot.stalls`) and of
        this control loop (a tick that came late: the command before it may have gone out
        late)."""
        return [*self.robot.stalls(self._leg_began), *self._late_ticks]

    def stall(self) -> float:
        """Seconds: the longest of `stalls()`, at most MAX_STALL."""
        return min(MAX_STALL, max((s.seconds for s in self.stalls()), default=0.0))

    def leeway(self, axis: tuple[float, float, float]) -> Leeway:
        """How far an honest robot may be from where the current leg's commands put it, for
        the stalls seen (bounds.CommandLedger.leeway; `axis` the leg's or the turn's)."""
        if self.ledger is None:
            return Leeway()
        lim = self.config.safety  # how fast the robot follows a change: the commands' caps
        accel = lim.max_angular_accel if axis[2] else lim.max_linear_accel
        return self.ledger.leeway(self.stalls(), axis, accel)

    @property
    def last_command(self) -> tuple[float, float, float]:
        """The velocity last commanded (vx, vy, wz): what the robot is doing as far as the
        commands go, known at once (a measured velocity lags on a late robot)."""
        return self._last_command

    def commanded(self) -> tuple[float, float, float]:
        """Where the commands of the current leg took the robot from where the leg began:
        metres along x and y (odom frame), radians turned (signed; see `begin_leg`)."""
        if self.ledger is None:
            return 0.0, 0.0, 0.0
        return self.ledger.offset(self.robot.now())

    def begin_leg(self, state: RobotState) -> None:
        """A straight leg or a turn starts from `state` (measured at rest): the commanded pose
        is taken from here, so small differences between commands and motion do not add up
        over a long path."""
        if self.ledger is None:
            self.ledger = CommandLedger(state.pose, self.robot.now())
        else:
            self.ledger.begin_leg(self.robot.now(), state.pose)
        self._leg_began, self._ticked, self._late_ticks = self.robot.now(), None, []

    def tick(self) -> None:
        """Wait one control period, then check cancellation and the time-out."""
        self._beat(None)
        self.robot.sleep(self.period)
        now = self.robot.now()
        if self._ticked is not None and now - self._ticked - self.period > 1e-3:
            late = now - self._ticked - self.period
            self._late_ticks.append(Stall(self._ticked, self._ticked + late))
        self._ticked = now
        self._beat(None)
        self.check()

    def _beat(self, moving: bool | None) -> bool:
        """The control loop's heartbeat (the watchdog's). True when the watchdog stopped the
        robot since the last beat (this loop stalled past `safety.watchdog_timeout`: a loaded
        machine); the loop then goes on from rest. The stop is sent again (a command held up
        in the stall may have gone out after the watchdog's), the commands count it from when
        the watchdog sent it, and the next command ramps up from zero."""
        trip = self.heartbeat(moving)
        if trip is None:
            return False
        self.robot.stop()
        if self.ledger is not None:
            lim = self.config.safety
            at = max(self.ledger.t, self.robot.now() - trip.ago)
            walked = self.ledger.halt(at, lim.max_linear_accel, lim.max_angular_accel)
            if self.env.budget is not None:
                self.env.budget.command(walked)
        self._last_command = (0.0, 0.0, 0.0)
        self.heartbeat(False)
        note = (
            "stopped when its control loop stalled (the watchdog, after "
            f"{trip.stalled:.2f} s: a loaded machine), and went on"
        )
        if note not in self.notes:
            self.notes.append(note)
        return True

    def drive(self, vx: float, vy: float, wz: float) -> None:
        """Send body-frame velocity within the safety caps (defence behind the plan check).

        Speeds are capped, and so is the change from the last command (acceleration caps);
        a command to stop is always sent at once.
        """
        s = self.config.safety
        asked = vx, vy, wz
        while True:
            self._beat(None)  # a stop by the watchdog since the last command: ramp up from zero
            vx, vy = _cap_vector(asked[0], asked[1], s.max_linear_speed)
            wz = max(-s.max_angular_speed, min(s.max_angular_speed, asked[2]))
            if vx or vy or wz:
                lx, ly, lw = self._last_command
                dx, dy = _cap_vector(vx - lx, vy - ly, s.max_linear_accel * self.period)
                dw = max(
                    -s.max_angular_accel * self.period,
                    min(s.max_angular_accel * self.period, wz - lw),
                )
                vx, vy, wz = lx + dx, ly + dy, lw + dw
            state = self.check()
            if not self._beat(bool(vx or vy or wz)):
                break  # else stopped by the watchdog during the check: again, from zero
        self._last_command = (vx, vy, wz)
        if self.ledger is None:
            self.ledger = CommandLedger(state.pose, self.robot.now())
            self._leg_began = self.robot.now()
        walked = self.ledger.set(self.robot.now(), vx, vy, wz)
        if self.env.budget is not None:
            self.env.budget.command(walked)
        try:
            self.robot.send_velocity(vx, vy, wz)
        except RobotError as blind:  # odometry went stale since `check`: as there
            if self.robot.last_state().connected:
                raise
            self._await_odometry(blind)

    def ensure_standing(self) -> None:
        """Stand up first when allowed (`motion.auto_stand`); from then on the step runs
        standing: `check` fails it if the robot stops standing (a fall)."""
        posture = self.robot.get_state().posture
        self._needs = Posture.STANDING
        if posture is Posture.STANDING:
            return
        if not self.config.motion.auto_stand:
            raise SkillError(f"the robot is {posture.value}; stand up first (body.stand)")
        self.robot.set_posture(Posture.STANDING)
        self.notes.append(f"stood up first (was {posture.value})")
        self.check()

    def camera_frame(self) -> CameraFrame | None:
        return self._camera()

    def say(self, text: str) -> Saying:
        """Say `text` through the agent's voice (cleaned, cut, rate-limited; see speech.py)."""
        if self._say is None:
            raise SkillError("nothing here can speak (no voice given to this step)")
        return self._say(text)


def _cap_vector(vx: float, vy: float, limit: float) -> tuple[float, float]:
    norm = math.hypot(vx, vy)
    if norm <= limit or norm == 0:
        return vx, vy
    return vx * limit / norm, vy * limit / norm
