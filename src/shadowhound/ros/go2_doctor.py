"""`shadowhound doctor --go2`: is the Go2 driver there, and will ShadowHound's commands reach it?

Watches the ROS graph and the driver's topics for a few seconds, then says, in words, what is
fine and what to fix: the driver node (go2_ros2_sdk's `go2_driver_node`; its absence first and
plainly, since some go2_ros2_sdk commits fail at start), each topic's type and type hash (a
hash that differs means Fast DDS silently drops every sample), odometry rate and age, which
velocity topic reaches the driver and why, postures from go2_states, and the battery source;
then the rest of a Go2 owner's stack (go2_doctor_stack.py): TF (odom -> base_link, SLAM's
map -> odom) and the map's frame, the object detector and its camera model, and the speaker.

`observe` (go2_doctor_watch.py: rclpy, imported lazily by the CLI) gathers an `Observation`
(go2_doctor_observation.py); `diagnose` (pure, here) turns it into findings, so every rule is
testable without ROS.
"""

from __future__ import annotations

from ..robot.go2 import api as go2_api
from ..robot.go2.motion import MAX_LATENCY
from ..robot.go2.topics import TWIST_TYPE, VELOCITY_TOPICS, choose_velocity_topic
from .go2_doctor_observation import Endpoint, Finding, Observation, topic_name
from .go2_doctor_stack import stack_findings

# The report's types live in go2_doctor_observation; they are imported from here too.
__all__ = [
    "BATTERY_TYPE",
    "ODOM_TYPE",
    "REQUEST_TYPE",
    "STATE_TYPE",
    "UPSTREAM_HASHES",
    "Endpoint",
    "Finding",
    "Observation",
    "diagnose",
]

ODOM_TYPE = "nav_msgs/msg/Odometry"
STATE_TYPE = "go2_interfaces/msg/Go2State"
REQUEST_TYPE = "go2_interfaces/msg/WebRtcReq"
BATTERY_TYPE = "sensor_msgs/msg/BatteryState"
# go2_ros2_sdk's own type hashes (ROS 2 Jazzy), as its go2_interfaces builds them.
UPSTREAM_HASHES = {
    STATE_TYPE: "RIHS01_26947c9882eb8f10418057a5777d99d4b3163c30f479a5626f034a65c3ea2848",
    REQUEST_TYPE: "RIHS01_1b3c5ffa35c3257e84c4282ceef9f14148d3c51579ea5e359d76f720613261fd",
}
MIN_ODOM_RATE = 5.0  # Hz below which the closed loop steers on too little
DRIVER_NODE = "go2_driver_node"  # go2_ros2_sdk's driver (presentation/go2_driver_node.py)
SIM_DRIVER_NODE = "shadowhound_sim_driver"  # `shadowhound sim-driver` (ros/sim_driver.py)
# Nodes robot.launch.py starts beside the driver (by the names it gives them, and their
# executables' own): up without it, the driver failed at start.
LAUNCH_NODES = (
    "twist_mux",
    "go2_robot_state_publisher",
    "go2_pointcloud_to_laserscan",
    "go2_rviz2",
    "lidar_to_pointcloud",
    "pointcloud_aggregator",
    "tts_node",
    "robot_state_publisher",
    "pointcloud_to_laserscan",
    "rviz2",
)
MAX_ODOM_AGE = 0.5  # seconds: the robot's odom_timeout default
BURST_GAP = 0.01  # seconds: poses closer than this came over the link in one burst


def diagnose(obs: Observation) -> list[Finding]:
    """Findings in the order a person would fix them: driver, types, data, velocity, battery,
    then the rest of the stack (go2_doctor_stack: TF and the map, detector, voice)."""
    out = [_driver(obs)]
    out += _types(obs)
    out.append(_odometry(obs))
    out.append(_postures(obs))
    out.append(_velocity(obs))
    out.append(_battery(obs))
    return out + stack_findings(obs)


def _driver(obs: Observation) -> Finding:
    """go2_ros2_sdk's driver node (any namespace), or the simulated one, said as such."""
    by_name = {
        name: sorted(n for n in obs.nodes if n.rsplit("/", 1)[-1] == name)
        for name in (DRIVER_NODE, SIM_DRIVER_NODE, *LAUNCH_NODES)
    }
    if by_name[DRIVER_NODE]:
        return Finding("ok", f"go2_ros2_sdk's driver: {', '.join(by_name[DRIVER_NODE])}")
    if by_name[SIM_DRIVER_NODE]:
        return Finding(
            "ok",
            f"driver: {', '.join(by_name[SIM_DRIVER_NODE])}, ShadowHound's simulated driver "
            f"(shadowhound sim-driver), not go2_ros2_sdk's {DRIVER_NODE}",
        )
    serving = {e.node for key in ("odom", "go2_states") for e in obs.publishers.get(key, [])}
    serving |= {e.node for e in obs.subscribers.get("webrtc_req", [])}
    if serving:
        return Finding(
            "warn",
            f"no {DRIVER_NODE} on the graph; {', '.join(sorted(serving))} serves the driver's "
            "topics (a driver under another name, or a recording?)",
            "fine if it drives the robot; otherwise start go2_ros2_sdk (docs/go2.md)",
        )
    launched = [n for name in LAUNCH_NODES for n in by_name[name]]
    ran = f" ({', '.join(launched)} up: the launch ran, its driver did not)" if launched else ""
    return Finding(
        "fail",
        f"no {DRIVER_NODE} on the graph: did the driver start? see docs/go2.md{ran}",
        "read the launch's output for the driver's error. go2_ros2_sdk's newest commits do "
        "not start (7f005bb and de12621: TabError in go2_connection.py; 9b67a62: an "
        "undefined name in connect()): check out 8d8785e. Run it with this ROS_DOMAIN_ID "
        "and RMW_IMPLEMENTATION; `shadowhound sim-driver` rehearses without a robot",
    )


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
                    f"{topic_name(obs, key)} has type {', '.join(wrong)}, expected {kind}",
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
                    f"{topic_name(obs, key)}: the driver's {kind} (type hash {differ[0]}) is not "
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
            out.append(Finding("ok", f"{topic_name(obs, key)}: {kind}, type hash matches"))
    return out


def _odometry(obs: Observation) -> Finding:
    times = obs.odom_receipts
    topic = topic_name(obs, "odom")
    if not times:
        return Finding(
            "fail",
            f"no odometry on {topic} in {obs.seconds:.0f} s",
            "check that the driver is connected to the robot (WebRTC allows one "
            "client: close the phone app) and that CONN_TYPE=webrtc",
        )
    # Poses that arrive within BURST_GAP of each other came in one burst (a busy Wi-Fi link,
    # go2_ros2_sdk #231): what the closed loop gets is a new burst every so often.
    bursts = [1]
    for a, b in zip(times, times[1:], strict=False):
        if b - a < BURST_GAP:
            bursts[-1] += 1
        else:
            bursts.append(1)
    span = times[-1] - times[0]
    rate = (len(times) - 1) / span if span > 0 else 0.0
    fresh = (len(bursts) - 1) / span if span > 0 else 0.0  # new poses a second, bursts as one
    age = obs.ended - times[-1]
    size = sum(bursts) / len(bursts)
    text = f"odometry on {topic}: {rate:.1f} Hz, last {age:.2f} s ago"
    if size >= 1.5:
        text += f", in bursts of {size:.1f} (a new pose every {1 / fresh:.2f} s)" if fresh else ""
    text += (
        "; its lag behind the robot shows only when the robot moves (the stamps are taken "
        "when the driver sends each pose): the node measures it (diagnostics odom_latency), "
        f"and missions work up to {MAX_LATENCY:g} s late, slower the later"
    )
    if age > MAX_ODOM_AGE:
        return Finding(
            "fail",
            text + " (stopped)",
            "odometry stopped: the driver lost the robot or the link is saturated; "
            "restart the driver, check Wi-Fi",
        )
    if fresh < MIN_ODOM_RATE:
        return Finding(
            "warn",
            text + f" (new poses below {MIN_ODOM_RATE:g} Hz)",
            "a busy link slows odometry (and usually delays it): motion stays accurate but "
            "slower to settle; a wired link or a quieter channel helps",
        )
    return Finding("ok", text)


def _postures(obs: Observation) -> Finding:
    topic = topic_name(obs, "go2_states")
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
        names={name: topic_name(obs, name) for name in VELOCITY_TOPICS},
    )
    if obs.cmd_vel_topic:
        key = obs.cmd_vel_topic
        subscribed = [e for e in obs.subscribers.get(key, []) if e.type == TWIST_TYPE]
        if topic_name(obs, key) == topic_name(obs, "cmd_vel") and route.topic != "cmd_vel":
            return Finding(
                "fail",
                f"velocity on {topic_name(obs, key)} (configured) reaches no driver: {route.why}",
                "leave cmd_vel_topic empty to follow the graph, or start twist_mux",
            )
        if subscribed:
            return Finding(
                "ok",
                f"velocity on {topic_name(obs, key)} (configured) reaches "
                f"{', '.join(sorted({e.node for e in subscribed}))}",
            )
        return Finding(
            "fail",
            f"nothing subscribes {topic_name(obs, key)} (configured cmd_vel_topic)",
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
    return Finding("ok", f"velocity goes to {topic_name(obs, route.topic)}: {route.why}")


def _battery(obs: Observation) -> Finding:
    if obs.battery_topic:
        topic = topic_name(obs, "battery")
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
