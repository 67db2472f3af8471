"""What `shadowhound doctor --go2` saw (`Observation`, gathered by go2_doctor_watch.py) and the
lines of its report (`Finding`, written by go2_doctor.py's rules). Pure Python."""

from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Endpoint:
    """One publisher or subscription in the graph; `node` is the node's full name."""

    node: str
    type: str
    hash: str = ""


@dataclass
class Observation:
    """What the doctor saw. Topic keys are the robot-relative names (odom, go2_states, ...)."""

    namespace: str = ""
    nodes: list[str] = field(default_factory=list)  # full names of every node on the graph
    names: dict[str, str] = field(default_factory=dict)  # key -> full topic name
    publishers: dict[str, list[Endpoint]] = field(default_factory=dict)
    subscribers: dict[str, list[Endpoint]] = field(default_factory=dict)
    local_hashes: dict[str, str] = field(default_factory=dict)  # type -> this build's hash
    seconds: float = 3.0  # how long it watched
    odom_receipts: list[float] = field(default_factory=list)  # monotonic, oldest first
    ended: float = 0.0  # monotonic time the watch ended
    states: list[tuple[int, float]] = field(default_factory=list)  # (mode, body height)
    cmd_vel_topic: str = ""  # configured ('' = discovered)
    battery_topic: str = ""  # configured ('' = none)
    battery_levels: list[float] = field(default_factory=list)  # percent, as received
    battery_elsewhere: list[str] = field(default_factory=list)  # BatteryState topics seen
    root_cmd_vel_subscribed: bool = False  # /cmd_vel (twist_mux is not namespaced)
    # The rest of a Go2 owner's stack (go2_doctor_stack.py); a topic left '' is not checked.
    coco_detections_topic: str = "detected_objects"
    camera_info_topic: str = "camera/camera_info"
    speech_topic: str = "/tts"
    map_topic: str = "map"
    unreadable: dict[str, str] = field(default_factory=dict)  # key -> why it was not read
    detection_receipts: list[float] = field(default_factory=list)  # monotonic, per array
    detection_classes: list[str] = field(default_factory=list)  # each box's class_id
    camera_infos: list[tuple[int, int, float]] = field(default_factory=list)  # width, height, fx
    map_frames: list[str] = field(default_factory=list)  # header.frame_id of each map
    tf: dict[tuple[str, str], int] = field(default_factory=dict)  # (parent, child) -> count
    tf_static: set[tuple[str, str]] = field(default_factory=set)  # (parent, child)
    root_webrtc_subscribed: bool = False  # /webrtc_req, where tts_node sends the audio


@dataclass(frozen=True)
class Finding:
    """One line of the report: `level` is ok, info (an optional part is not there), warn or
    fail (a mission could not work); `fix` says what to do."""

    level: str
    what: str
    fix: str = ""

    def __str__(self) -> str:
        return f"{self.level:<4} {self.what}" + (f"\n     fix: {self.fix}" if self.fix else "")


def topic_name(obs: Observation, key: str) -> str:
    """The full name of the topic watched under `key` (the key itself when not resolved)."""
    return obs.names.get(key, key)
