"""The simulated driver's injected faults: what a fault message asks for, and how it changes
the odometry the driver publishes while the truth stays true.

A message on `sim_driver/fault` replaces every fault at once (`{}` clears them). Besides the
stream faults (`odom`, `states`, `camera` off; `delay_ms` on commands; `drop_commands`), it may
ask for odometry that lies while it still arrives, as a real Go2's does:

- `jump`: {"x", "y" metres, "yaw_deg"}: the published frame moves by this, about where the
  robot is when it fires (a SLAM relocalization, two SDKs on one network);
- `freeze`: the published pose stays where it was when it fired, with fresh stamps;
- `nan`: the next N odometry messages carry NaN instead of a pose;
- `clock_step`: seconds added to every odometry stamp from then on (negative: set back);
- `fall`: the robot falls (Damping, lying, Moves ignored) as it fires;
- `stall_ms`: the driver's process stalls this long as it fires, as on a loaded machine: no
  command acts and no odometry goes out meanwhile (what came in acts, and what was due goes
  out, when it ends); the robot walks on as last told, and the truth keeps coming;
- `slam_error`: {"x", "y" metres, "yaw_deg"}: with `--slam`, SLAM's map -> odom is published
  this far off (SLAM mislocalized; the robot's map pose is off by it): clearing it makes the
  correction jump back, as a loop closure does. It takes effect at once;
- `after_m`, `after_deg`: these fire once the true robot has moved that far (straight line)
  or turned that much from where it was when the message arrived (default: at once).

Pure Python: the driver hands in each true pose it is about to publish.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass
from typing import Any

from ..state import normalize_angle

_FLAGS = ("odom", "states", "camera", "drop_commands", "freeze", "fall")
_KNOWN = (
    *_FLAGS,
    "delay_ms",
    "stall_ms",
    "jump",
    "nan",
    "clock_step",
    "after_m",
    "after_deg",
    "slam_error",
)


@dataclass(frozen=True)
class Faults:
    """Injected faults (all off by default)."""

    odom: bool = True
    states: bool = True
    camera: bool = True
    delay: float = 0.0  # seconds every command is held back
    drop_commands: bool = False
    jump: tuple[float, float, float] | None = None  # x, y (m), yaw (rad) the frame moves by
    freeze: bool = False
    nan: int = 0  # odometry messages sent as NaN
    clock_step: float = 0.0  # seconds added to odometry stamps
    fall: bool = False
    stall: float = 0.0  # seconds the driver's process stalls once, as the faults fire
    after_m: float = 0.0  # metres of true motion before the odometry faults and fall fire
    after_deg: float = 0.0  # degrees of true turning, likewise
    slam_error: tuple[float, float, float] | None = None  # map -> odom off by x, y, yaw

    @property
    def lies(self) -> bool:
        """Odometry faults or a fall that wait for their moment (`after_m`, `after_deg`)."""
        return bool(
            self.jump or self.freeze or self.nan or self.clock_step or self.fall or self.stall
        )

    @classmethod
    def from_json(cls, text: str) -> Faults:
        """Parse a fault message; raises ValueError naming what is wrong and what is allowed."""
        data = json.loads(text) if text.strip() else {}
        if not isinstance(data, dict):
            raise ValueError("a fault message must be a JSON object")
        unknown = set(data) - set(_KNOWN)
        if unknown:
            raise ValueError(f"unknown fault(s) {sorted(unknown)}; known: {', '.join(_KNOWN)}")
        flags = {k: data[k] for k in _FLAGS if k in data}
        if not all(isinstance(v, bool) for v in flags.values()):
            raise ValueError(f"{', '.join(_FLAGS)} take true or false")
        out: dict[str, Any] = dict(flags)
        out["delay"] = _number(data, "delay_ms", 0, 10_000, "a number of milliseconds") / 1000.0
        out["stall"] = _number(data, "stall_ms", 0, 5_000, "a number of milliseconds") / 1000.0
        out["nan"] = int(_number(data, "nan", 0, 10_000, "a whole number of messages"))
        if out["nan"] != data.get("nan", 0):
            raise ValueError("nan must be a whole number of messages in 0..10000")
        out["clock_step"] = _number(data, "clock_step", -100, 100, "seconds")
        out["after_m"] = _number(data, "after_m", 0, 100, "metres")
        out["after_deg"] = _number(data, "after_deg", 0, 3600, "degrees")
        for key in ("jump", "slam_error"):
            if key in data:
                out[key] = _motion(data[key], key)
        return cls(**out)

    def to_dict(self) -> dict[str, Any]:
        """As the truth record shows them (JSON)."""
        out = {k: getattr(self, k) for k in _FLAGS}
        out.update(delay_ms=self.delay * 1000.0, nan=self.nan, clock_step=self.clock_step)
        out.update(stall_ms=self.stall * 1000.0)
        out.update(after_m=self.after_m, after_deg=self.after_deg)
        for key in ("jump", "slam_error"):
            value = getattr(self, key)
            out[key] = (
                None
                if value is None
                else {"x": value[0], "y": value[1], "yaw_deg": math.degrees(value[2])}
            )
        return out


def _motion(value: Any, key: str) -> tuple[float, float, float]:
    """A {"x", "y", "yaw_deg"} object as (x, y, yaw radians)."""
    if not isinstance(value, dict) or set(value) - {"x", "y", "yaw_deg"}:
        raise ValueError(f'{key} must be an object {{"x": m, "y": m, "yaw_deg": degrees}}')
    return (
        _number(value, "x", -1000, 1000, "metres", f"{key}.x"),
        _number(value, "y", -1000, 1000, "metres", f"{key}.y"),
        math.radians(_number(value, "yaw_deg", -360, 360, "degrees", f"{key}.yaw_deg")),
    )


def _number(
    data: dict[str, Any], key: str, low: float, high: float, unit: str, name: str = ""
) -> float:
    value = data.get(key, 0)
    if (
        isinstance(value, bool)
        or not isinstance(value, (int, float))
        or not math.isfinite(value)
        or not low <= value <= high
    ):
        raise ValueError(f"{name or key} must be {unit} in {low:g}..{high:g}, got {value!r}")
    return float(value)


Pose = tuple[float, float, float]


class LyingOdometry:
    """Turns true poses into the poses the faults publish. `arm` when a fault message
    arrives (with the true pose then); `publish(pose)` for each odometry message gives the
    pose to publish (None: a NaN message) and the stamp offset; `fired` says whether the
    odometry faults are in force (the driver makes the robot fall once, when they fire)."""

    def __init__(self) -> None:
        self.faults = Faults()
        self._armed_at: Pose = (0.0, 0.0, 0.0)
        self._turned = 0.0
        self._last_yaw = 0.0
        self.fired = False
        self._frame: tuple[Pose, Pose] | None = None  # (the pose it fired at, the offset)
        self._frozen: Pose | None = None
        self._nan_left = 0

    def arm(self, faults: Faults, pose: Pose) -> None:
        self.faults, self._armed_at = faults, pose
        self._turned, self._last_yaw = 0.0, pose[2]
        self.fired = False
        self._frame, self._frozen, self._nan_left = None, None, 0

    def publish(self, pose: Pose) -> tuple[Pose | None, float]:
        """The pose to publish for the true `pose` (None: NaN), and seconds to add to the
        stamp. Returns True in `fired` the first time the faults take effect."""
        f = self.faults
        if not f.lies:
            return pose, 0.0
        if not self.fired:
            self._turned += abs(normalize_angle(pose[2] - self._last_yaw))
            self._last_yaw = pose[2]
            moved = math.hypot(pose[0] - self._armed_at[0], pose[1] - self._armed_at[1])
            if moved < f.after_m or math.degrees(self._turned) < f.after_deg:
                return pose, 0.0
            self.fired = True
            if f.jump is not None:
                self._frame = (pose, f.jump)
            self._nan_left = f.nan
        shown = self._moved(pose)
        if f.freeze:
            self._frozen = self._frozen or shown
            shown = self._frozen
        if self._nan_left > 0:
            self._nan_left -= 1
            return None, f.clock_step
        return shown, f.clock_step

    def _moved(self, pose: Pose) -> Pose:
        """The pose in the jumped frame: rotated by the jump about where it fired, shifted."""
        if self._frame is None:
            return pose
        (fx, fy, _), (dx, dy, dyaw) = self._frame
        c, s = math.cos(dyaw), math.sin(dyaw)
        rx, ry = pose[0] - fx, pose[1] - fy
        return (
            fx + dx + rx * c - ry * s,
            fy + dy + rx * s + ry * c,
            normalize_angle(pose[2] + dyaw),
        )
