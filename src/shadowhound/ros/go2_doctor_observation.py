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


@dataclass(frozen=True)
class Finding:
    """One line of the report: `level` is ok, warn or fail; `fix` says what to do."""

    level: str
    what: str
    fix: str = ""

    def __str__(self) -> str:
        return f"{self.level:<4} {self.what}" + (f"\n     fix: {self.fix}" if self.fix else "")


def topic_name(obs: Observation, key: str) -> str:
    """The full name of the topic watched under `key` (the key itself when not resolved)."""
    return obs.names.get(key, key)
