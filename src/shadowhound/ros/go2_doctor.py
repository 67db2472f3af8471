"""`shadowhound doctor --go2`: is the Go2 driver there, and will ShadowHound's commands reach it?

Watches the ROS graph and the driver's topics for a few seconds, then says, in words, what is
fine and what to fix: the driver node, each topic's type and type hash (a hash that differs
means Fast DDS silently drops every sample), odometry rate and age, which velocity topic
reaches the driver, postures from go2_states, and the battery source.

`observe` (rclpy, imported lazily by the CLI) gathers an `Observation`; `diagnose` (pure) turns
it into findings, so every rule is testable without ROS.
"""

from __future__ import annotations

import time
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Any

from ..robot import go2_api
from ..robot.go2_topics import TWIST_TYPE, VELOCITY_TOPICS, choose_velocity_topic, node_name

ODOM_TYPE = "nav_msgs/msg/Odometry"
STATE_TYPE = "go2_interfaces/msg/Go2State"
REQUEST_TYPE = "go2_interfaces/msg/WebRtcReq"
BATTERY_TYPE = "sensor_msgs/msg/BatteryState"
BATTERY_GRACE = 5.0  # extra seconds to wait for a slow battery topic
# go2_ros2_sdk's own type hashes (ROS 2 Jazzy), as its go2_interfaces builds them.
UPSTREAM_HASHES = {
    STATE_TYPE: "RIHS01_26947c9882eb8f10418057a5777d99d4b3163c30f479a5626f034a65c3ea2848",
    REQUEST_TYPE: "RIHS01_1b3c5ffa35c3257e84c4282ceef9f14148d3c51579ea5e359d76f720613261fd",
}
MIN_ODOM_RATE = 5.0  # Hz below which the closed loop steers on too little
MAX_ODOM_AGE = 0.5  # seconds: the robot's odom_timeout default


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


def diagnose(obs: Observation) -> list[Finding]:
    """Findings in the order a person would fix them: driver, types, data, velocity, battery."""
    out = [_driver(obs)]
    out += _types(obs)
    out.append(_odometry(obs))
    out.append(_postures(obs))
    out.append(_velocity(obs))
    out.append(_battery(obs))
    return out


def _name(obs: Observation, key: str) -> str:
    return obs.names.get(key, key)


def _driver(obs: Observation) -> Finding:
    nodes = sorted(
        {e.node for key in ("odom", "go2_states") for e in obs.publishers.get(key, [])}
        | {e.node for e in obs.subscribers.get("webrtc_req", [])}
    )
    if not nodes:
        return Finding(
            "fail",
            f"no Go2 driver: nothing publishes {_name(obs, 'odom')} or "
            f"{_name(obs, 'go2_states')}, nothing subscribes "
            f"{_name(obs, 'webrtc_req')}",
            "start go2_ros2_sdk (ros2 launch go2_robot_sdk robot.launch.py) or "
            "`shadowhound sim-driver`, in the same ROS_DOMAIN_ID and "
            "RMW_IMPLEMENTATION; with several robots give --namespace robot0",
        )
    return Finding("ok", f"driver node(s): {', '.join(nodes)}")


def _types(obs: Observation) -> list[Finding]:
    out = []
    wanted = (
        ("odom", ODOM_TYPE, obs.publishers),
        ("go2_states", STATE_TYPE, obs.publishers),
        ("webrtc_req", REQUEST_TYPE, obs.subscribers),
    )
    for key, kind, side in wanted:
        ends = side.get(key, [])
        wrong = sorted({e.type for e in ends if e.type != kind})
        if wrong:
            out.append(
                Finding(
                    "fail",
                    f"{_name(obs, key)} has type {', '.join(wrong)}, expected {kind}",
                    "point ShadowHound at the driver's topic (odom_topic, "
                    "go2_states_topic, webrtc_topic)",
                )
            )
            continue
        local = obs.local_hashes.get(kind, "")
        differ = sorted({e.hash for e in ends if e.hash and local and e.hash != local})
        if differ:
            out.append(
                Finding(
                    "fail",
                    f"{_name(obs, key)}: the driver's {kind} (type hash {differ[0]}) is not "
                    f"the one ShadowHound uses ({local}); DDS drops every sample although "
                    "the topic looks matched",
                    "source the go2_ros2_sdk workspace the driver runs from before starting "
                    "ShadowHound, or rebuild ShadowHound's copy (scripts/build_ros.sh)",
                )
            )
            continue
        upstream = UPSTREAM_HASHES.get(kind)
        if upstream and local and local != upstream:
            out.append(
                Finding(
                    "warn",
                    f"this build's {kind} (type hash {local}) is not go2_ros2_sdk's ({upstream})",
                    "rebuild go2_interfaces from go2_ros2_sdk's message files "
                    "(scripts/build_ros.sh)",
                )
            )
        elif ends:
            out.append(Finding("ok", f"{_name(obs, key)}: {kind}, type hash matches"))
    return out


def _odometry(obs: Observation) -> Finding:
    times = obs.odom_receipts
    topic = _name(obs, "odom")
    if not times:
        return Finding(
            "fail",
            f"no odometry on {topic} in {obs.seconds:.0f} s",
            "check that the driver is connected to the robot (WebRTC allows one "
            "client: close the phone app) and that CONN_TYPE=webrtc",
        )
    gaps = sorted(b - a for a, b in zip(times, times[1:], strict=False) if b > a)
    rate = 1.0 / gaps[len(gaps) // 2] if gaps else 0.0  # the median: bursts do not count
    age = obs.ended - times[-1]
    text = f"odometry on {topic}: {rate:.1f} Hz, last {age:.2f} s ago"
    if age > MAX_ODOM_AGE:
        return Finding(
            "fail",
            text + " (stopped)",
            "odometry stopped: the driver lost the robot or the link is saturated; "
            "restart the driver, check Wi-Fi",
        )
    if rate < MIN_ODOM_RATE:
        return Finding(
            "warn",
            text + f" (below {MIN_ODOM_RATE:g} Hz)",
            "a busy link slows odometry: motion stays accurate but slower to settle",
        )
    return Finding("ok", text)


def _postures(obs: Observation) -> Finding:
    topic = _name(obs, "go2_states")
    if not obs.states:
        return Finding(
            "fail",
            f"no go2_states on {topic}: postures cannot be read",
            "check the driver (and the type hash above)",
        )
    mode, height = obs.states[-1]
    posture = go2_api.posture_of(mode, height)
    seen = posture.value if posture else "changing posture"
    return Finding("ok", f"go2_states on {topic}: mode {mode}, body height {height:.2f} m ({seen})")


def _velocity(obs: Observation) -> Finding:
    def on(side: dict[str, list[Endpoint]]) -> dict[str, list[tuple[str, str]]]:
        return {name: [(e.node, e.type) for e in side.get(name, [])] for name in VELOCITY_TOPICS}

    route = choose_velocity_topic(
        on(obs.subscribers),
        on(obs.publishers),
        names={name: _name(obs, name) for name in VELOCITY_TOPICS},
    )
    if obs.cmd_vel_topic:
        key = obs.cmd_vel_topic
        subscribed = [e for e in obs.subscribers.get(key, []) if e.type == TWIST_TYPE]
        if _name(obs, key) == _name(obs, "cmd_vel") and route.topic != "cmd_vel":
            return Finding(
                "fail",
                f"velocity on {_name(obs, key)} (configured) reaches no driver: {route.why}",
                "leave cmd_vel_topic empty to follow the graph, or start twist_mux",
            )
        if subscribed:
            return Finding(
                "ok",
                f"velocity on {_name(obs, key)} (configured) reaches "
                f"{', '.join(sorted({e.node for e in subscribed}))}",
            )
        return Finding(
            "fail",
            f"nothing subscribes {_name(obs, key)} (configured cmd_vel_topic)",
            "leave cmd_vel_topic empty to follow the graph",
        )
    if not route.reaches:
        hint = ""
        if obs.namespace and obs.root_cmd_vel_subscribed:
            hint = (
                " (twist_mux listens on /cmd_vel, but it is not namespaced: it does not "
                f"reach the driver of {obs.namespace})"
            )
        return Finding(
            "fail",
            f"velocity would reach nothing: {route.why}{hint}",
            "start the driver (it listens on cmd_vel_out) and check --namespace",
        )
    return Finding("ok", f"velocity goes to {_name(obs, route.topic)}: {route.why}")


def _battery(obs: Observation) -> Finding:
    if obs.battery_topic:
        topic = _name(obs, "battery")
        if obs.battery_levels:
            return Finding("ok", f"battery from {topic}: {obs.battery_levels[-1]:.0f}%")
        return Finding(
            "warn",
            f"no battery level on {topic} (configured battery_topic): the "
            "battery is reported unknown",
            "publish sensor_msgs/BatteryState there (percentage 0..1)",
        )
    elsewhere = (
        f" (BatteryState seen on {', '.join(obs.battery_elsewhere)})"
        if obs.battery_elsewhere
        else ""
    )
    return Finding(
        "warn",
        "no battery source: the battery is reported unknown and the "
        f"battery floor cannot act{elsewhere}",
        "go2_ros2_sdk publishes no battery level; set battery_topic to a "
        "sensor_msgs/BatteryState topic if you have one",
    )


# -- watching the graph (rclpy) --------------------------------------------------------------


def require_ros() -> None:
    """Raise ImportError naming what is missing when ROS 2 or go2_interfaces is not installed
    (before anything is printed about watching topics)."""
    import rclpy  # noqa: F401
    from go2_interfaces.msg import Go2State  # noqa: F401


def observe(
    namespace: str = "", *, seconds: float = 3.0, cmd_vel_topic: str = "", battery_topic: str = ""
) -> Observation:
    """Watch the driver's topics for `seconds` in a private rclpy context."""
    import rclpy
    from go2_interfaces.msg import Go2State, WebRtcReq
    from nav_msgs.msg import Odometry
    from rclpy.context import Context
    from rclpy.executors import SingleThreadedExecutor
    from rclpy.node import Node
    from rclpy.qos import QoSProfile, ReliabilityPolicy
    from sensor_msgs.msg import BatteryState

    obs = Observation(
        namespace=namespace.strip("/"),
        seconds=seconds,
        cmd_vel_topic=cmd_vel_topic,
        battery_topic=battery_topic,
    )
    context = Context()
    rclpy.init(context=context)
    node = Node(
        "shadowhound_doctor",
        namespace="/" + obs.namespace,
        context=context,
        use_global_arguments=False,
        start_parameter_services=False,
    )
    qos = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)
    keys = ["odom", "go2_states", "webrtc_req", *VELOCITY_TOPICS]
    if cmd_vel_topic and cmd_vel_topic not in keys:
        keys.append(cmd_vel_topic)
    obs.names = {k: node.resolve_topic_name(k) for k in keys}
    if battery_topic:
        obs.names["battery"] = node.resolve_topic_name(battery_topic)
    node.create_subscription(
        Odometry, "odom", lambda _m: obs.odom_receipts.append(time.monotonic()), qos
    )

    def on_state(msg: Any) -> None:
        obs.states.append((int(msg.mode), float(msg.body_height)))

    def on_battery(msg: Any) -> None:
        obs.battery_levels.append(float(msg.percentage) * 100.0)

    node.create_subscription(Go2State, "go2_states", on_state, qos)
    probe = node.create_publisher(WebRtcReq, "shadowhound_doctor/type_probe", qos)
    if battery_topic:
        node.create_subscription(BatteryState, battery_topic, on_battery, qos)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    try:
        end = time.monotonic() + seconds
        while time.monotonic() < end:
            executor.spin_once(timeout_sec=0.05)
        # Battery sources often publish at 1 Hz or slower: give a configured one that has a
        # publisher up to BATTERY_GRACE more seconds for its first message.
        if battery_topic and node.get_publishers_info_by_topic(obs.names["battery"]):
            grace = time.monotonic() + BATTERY_GRACE
            while not obs.battery_levels and time.monotonic() < grace:
                executor.spin_once(timeout_sec=0.05)
        obs.ended = time.monotonic()
        me = node.get_fully_qualified_name()
        for key, full in obs.names.items():
            obs.publishers[key] = _endpoints(node.get_publishers_info_by_topic(full), me)
            obs.subscribers[key] = _endpoints(node.get_subscriptions_info_by_topic(full), me)
        own = [
            *node.get_subscriptions_info_by_topic(obs.names["go2_states"]),
            *node.get_subscriptions_info_by_topic(obs.names["odom"]),
            *node.get_publishers_info_by_topic(probe.topic_name),
        ]
        obs.local_hashes = {
            i.topic_type: str(i.topic_type_hash)
            for i in own
            if node_name(i.node_namespace, i.node_name) == me
        }
        obs.root_cmd_vel_subscribed = bool(node.get_subscriptions_info_by_topic("/cmd_vel"))
        obs.battery_elsewhere = sorted(
            n for n, types in node.get_topic_names_and_types() if BATTERY_TYPE in types
        )
    finally:
        executor.shutdown(timeout_sec=1.0)
        node.destroy_node()
        rclpy.try_shutdown(context=context)
    return obs


def _endpoints(infos: Sequence[Any], me: str) -> list[Endpoint]:
    ends = (
        Endpoint(node_name(i.node_namespace, i.node_name), i.topic_type, str(i.topic_type_hash))
        for i in infos
    )
    return [e for e in ends if e.node != me]
