"""The robot backends' settings: one typed model per backend, chosen by `type` in the profile
(`robot: go2` or `robot: {type: go2, namespace: robot0, ...}`). robot/factory.py builds the
robot from them; ROS parameters only fill them (ros/params.py).

Every backend's settings also say which robot this is (`RobotId`, from `name`, else the type and
the namespace): what the robot remembers (places, sightings, missions) belongs to it, and only
its own memories are ever goals (docs/memory.md).
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass
from typing import Annotated, ClassVar, Literal

from pydantic import BaseModel, ConfigDict, Field, model_validator

__all__ = [
    "ESTOP_RELEASE_TOPIC",
    "ESTOP_TOPIC",
    "GO2_MOTION",
    "ROBOT_TYPES",
    "Go2EduRobotSettings",
    "Go2RobotSettings",
    "ROBOT_NAME",
    "ROBOT_NAME_RULE",
    "RobotId",
    "RobotSettings",
    "SimRobotSettings",
]

# The Go2's odometry-driven motion: what the motion section takes for a Go2 when the profile and
# the environment leave it unset (its closed loop needs finer tolerances than the simulator's).
GO2_MOTION: dict[str, float] = {
    "position_tolerance": 0.02,
    "yaw_tolerance": math.radians(0.5),
    "control_rate_hz": 10.0,
}
ESTOP_TOPIC = "/shadowhound/estop"  # std_msgs/Empty: stop now and latch
ESTOP_RELEASE_TOPIC = "/shadowhound/estop_release"  # std_msgs/Empty: a person releases it


# A robot's name: what people call it and what its memories carry ("sim", "go2:robot0",
# "kitchen-dog"). No spaces, so it reads the same in a log, a listing and a ROS parameter.
ROBOT_NAME = re.compile(r"^[A-Za-z0-9][A-Za-z0-9_.:/-]{0,63}$")
ROBOT_NAME_RULE = "1 to 64 letters, digits and _ . : / - (starting with a letter or digit)"


@dataclass(frozen=True)
class RobotId:
    """Which robot made a memory: every place taught, object seen and mission run carries it,
    and only the current robot's own are goals. From the robot's settings
    (`settings.robot.identity`): its `name`, else its type and namespace (`sim`, `go2`,
    `go2_edu`, `go2:robot0`). Raises ValueError for a name outside `ROBOT_NAME`."""

    name: str

    def __post_init__(self) -> None:
        if not ROBOT_NAME.match(self.name):
            raise ValueError(f"a robot's name is {ROBOT_NAME_RULE}, got {self.name!r}")

    def __str__(self) -> str:
        return self.name


def _derived_name(kind: str, namespace: str) -> str:
    """The default name: the backend type, with the ROS namespace when there is one (two Go2s
    of one fleet are two robots)."""
    where = namespace.strip("/")
    return f"{kind}:{where}" if where else kind


class _Backend(BaseModel):
    """A robot backend's settings: `type` names the backend (`settings.robot.type`)."""

    model_config = ConfigDict(extra="forbid", validate_assignment=True)
    # The motion section's defaults this robot needs where the profile and the environment
    # leave them unset (config.ShadowHoundConfig applies them); none: the motion section's own.
    motion_defaults: ClassVar[dict[str, float]] = {}
    name: str = Field(
        "",
        description="which robot this is to memory (its places, sightings and missions); "
        "'' = its type and namespace: sim, go2, go2_edu, go2:robot0",
    )

    @property
    def identity(self) -> RobotId:
        """Which robot these settings drive: `name`, else the type and namespace."""
        return RobotId(self.name or self._default_name())

    def _default_name(self) -> str:
        raise NotImplementedError  # every backend says its own

    @model_validator(mode="after")
    def _named(self) -> _Backend:
        """A name outside ROBOT_NAME, or a namespace no name can be made of (a space in it),
        is refused at load, saying what a name may be."""
        if self.name:
            RobotId(self.name)
            return self
        try:
            RobotId(self._default_name())
        except ValueError as exc:
            raise ValueError(f"{exc} (made of the namespace): set robot.name") from exc
        return self


class SimRobotSettings(_Backend):
    """The simulated Go2 (SimRobot); its world and physics are the `sim` section."""

    type: Literal["sim"] = "sim"

    def _default_name(self) -> str:
        return _derived_name(self.type, "")


class Go2RobotSettings(_Backend):
    """A Unitree Go2 through go2_ros2_sdk's ROS 2 topics (docs/go2.md). Topic names are
    relative to `namespace` (e.g. `robot0`, go2_ros2_sdk's multi-robot prefix) unless they start
    with '/'; an empty `cmd_vel_topic` is discovered; an empty optional topic turns it off."""

    type: Literal["go2"] = "go2"
    motion_defaults: ClassVar[dict[str, float]] = GO2_MOTION
    namespace: str = ""
    cmd_vel_topic: str = ""
    webrtc_topic: str = "webrtc_req"
    odom_topic: str = "odom"
    state_topic: str = "go2_states"
    camera_topic: str = "camera/image_raw"
    battery_topic: str = Field("", description="sensor_msgs/BatteryState; '' = battery unknown")
    detections_topic: str = Field("", description="shadowhound_interfaces/DetectionArray")
    detector_classes: tuple[str, ...] = Field(
        (), description="names the detector can report: what a search may look for"
    )
    coco_detections_topic: str = Field(
        "", description="vision_msgs/Detection2DArray (coco_detector: detected_objects)"
    )
    camera_info_topic: str = "camera/camera_info"
    camera_x: float = Field(0.3, ge=-2, le=2, description="the camera's mount, metres ahead")
    camera_y: float = Field(0.0, ge=-2, le=2, description="metres left of the body's centre")
    camera_yaw: float = Field(0.0, ge=-math.pi, le=math.pi, description="radians, left +")
    coco_max_range: float = Field(6.0, ge=0.5, le=30, description="metres; beyond: a bearing")
    battery_timeout: float = Field(30.0, gt=0, description="seconds a battery reading lasts")
    odom_timeout: float = Field(0.5, gt=0, description="seconds without odometry: blind")
    odom_latency: float | None = Field(
        None, ge=0, le=5, description="seconds odometry lags the robot; None = measured"
    )
    command_timeout: float = Field(10.0, gt=0, description="seconds a posture may take")
    max_linear_speed: float = Field(1.0, gt=0, le=3, description="m/s, the Go2's own cap")
    max_angular_speed: float = Field(2.0, gt=0, le=6, description="rad/s")
    linear_accel: float = Field(1.0, gt=0, description="m/s^2 (the tracker's model)")
    angular_accel: float = Field(3.0, gt=0, description="rad/s^2")
    firmware_tricks: bool = Field(False, description="flips, handstand: firmware that has them")
    map_topic: str = Field("map", description="nav_msgs/OccupancyGrid; '' = no map")
    scan_topic: str = Field("scan", description="sensor_msgs/LaserScan; '' = none")
    scan_timeout: float = Field(1.0, gt=0, description="seconds a scan stays usable")
    nav2_action: str = Field("navigate_to_pose", description="Nav2's action; '' = no Nav2")
    robot_radius: float = Field(0.35, gt=0, le=2, description="metres kept from obstacles")
    node_name: str = "shadowhound_go2"
    estop_topic: str = Field(ESTOP_TOPIC, description="std_msgs/Empty; '' = not listened to")
    estop_release_topic: str = ESTOP_RELEASE_TOPIC
    speech_topic: str = Field("/tts", description="std_msgs/String for tts_node; '' = mute")
    map_frame: str = Field("map", description="SLAM's map frame on /tf; '' = read no TF")

    def _default_name(self) -> str:
        return _derived_name(self.type, self.namespace)


class Go2EduRobotSettings(_Backend):
    """A Unitree Go2 EDU through Unitree's own ROS 2 interface (unitree_ros2, CycloneDDS on the
    robot): sport requests out, sport and low state in. Topic names are relative to `namespace`
    unless they start with '/' (the robot's own are at the root)."""

    type: Literal["go2_edu"] = "go2_edu"
    motion_defaults: ClassVar[dict[str, float]] = GO2_MOTION
    namespace: str = ""
    request_topic: str = Field("/api/sport/request", description="unitree_api/Request out")
    state_topic: str = Field("lf/sportmodestate", description="unitree_go/SportModeState in")
    low_state_topic: str = Field("lf/lowstate", description="unitree_go/LowState (battery) in")
    battery_timeout: float = Field(30.0, gt=0, description="seconds a battery reading lasts")
    state_timeout: float = Field(0.5, gt=0, description="seconds without sport state: blind")
    state_latency: float | None = Field(
        None, ge=0, le=5, description="seconds the sport state lags the robot; None = measured"
    )
    command_timeout: float = Field(10.0, gt=0, description="seconds a posture may take")
    max_linear_speed: float = Field(1.0, gt=0, le=3, description="m/s, the Go2's own cap")
    max_angular_speed: float = Field(2.0, gt=0, le=6, description="rad/s")
    linear_accel: float = Field(1.0, gt=0, description="m/s^2 (the tracker's model)")
    angular_accel: float = Field(3.0, gt=0, description="rad/s^2")
    node_name: str = "shadowhound_go2_edu"

    def _default_name(self) -> str:
        return _derived_name(self.type, self.namespace)


RobotSettings = Annotated[
    SimRobotSettings | Go2RobotSettings | Go2EduRobotSettings, Field(discriminator="type")
]
ROBOT_TYPES: tuple[str, ...] = ("sim", "go2", "go2_edu")
