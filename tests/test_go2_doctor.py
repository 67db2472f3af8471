"""`shadowhound doctor --go2`: its rules on observations (pure; over DDS: tests/ros)."""

from __future__ import annotations

from shadowhound.robot.go2.topics import TWIST_TYPE
from shadowhound.ros.go2_doctor import (
    ODOM_TYPE,
    REQUEST_TYPE,
    STATE_TYPE,
    UPSTREAM_HASHES,
    Endpoint,
    Observation,
    diagnose,
)

DRIVER = "/go2_driver_node"
MUX = "/twist_mux"


def healthy(**changes: object) -> Observation:
    obs = Observation(
        names={k: "/" + k for k in ("odom", "go2_states", "webrtc_req", "cmd_vel", "cmd_vel_out")},
        publishers={
            "odom": [Endpoint(DRIVER, ODOM_TYPE)],
            "go2_states": [Endpoint(DRIVER, STATE_TYPE, UPSTREAM_HASHES[STATE_TYPE])],
            "cmd_vel_out": [Endpoint(MUX, TWIST_TYPE)],
        },
        subscribers={
            "webrtc_req": [Endpoint(DRIVER, REQUEST_TYPE, UPSTREAM_HASHES[REQUEST_TYPE])],
            "cmd_vel": [Endpoint(MUX, TWIST_TYPE)],
            "cmd_vel_out": [Endpoint(DRIVER, TWIST_TYPE)],
        },
        nodes=[DRIVER, MUX],
        local_hashes=dict(UPSTREAM_HASHES),
        odom_receipts=[i * 0.05 for i in range(60)],
        ended=3.0,
        states=[(1, 0.32)],
    )
    for key, value in changes.items():
        setattr(obs, key, value)
    return obs


def lines(obs: Observation) -> list[str]:
    return [str(f) for f in diagnose(obs)]


def test_a_healthy_driver_passes_and_says_where_velocity_goes() -> None:
    found = lines(healthy())
    assert all(not line.startswith("fail") for line in found), found
    assert "ok   go2_ros2_sdk's driver: /go2_driver_node" in found
    assert "ok   velocity goes to /cmd_vel: /twist_mux relays it to /cmd_vel_out" in found
    assert any("odometry on /odom: 20.0 Hz" in line for line in found)
    assert any("(standing)" in line for line in found)
    assert any(line.startswith("warn no battery source") for line in found)


def test_no_driver_says_so_plainly_and_which_commit_starts() -> None:
    found = lines(healthy(nodes=[], publishers={}, subscribers={}, odom_receipts=[], states=[]))
    first = found[0]
    assert first.startswith(
        "fail no go2_driver_node on the graph: did the driver start? see docs/go2.md"
    ), first
    assert "check out 8d8785e" in first and "TabError" in first and "ROS_DOMAIN_ID" in first
    assert any(
        line.startswith("fail velocity would reach nothing: nothing subscribes /cmd_vel_out")
        for line in found
    )


def test_a_different_type_hash_is_named_with_the_fix() -> None:
    stale = "RIHS01_" + "0" * 64
    found = lines(healthy(local_hashes={**UPSTREAM_HASHES, STATE_TYPE: stale}))
    text = next(line for line in found if "DDS drops every sample" in line)
    assert text.startswith("fail /go2_states") and "source the go2_ros2_sdk workspace" in text


def test_stopped_odometry_fails_and_slow_odometry_warns() -> None:
    stopped = lines(healthy(ended=5.0))
    assert any(
        line.startswith("fail odometry on /odom") and "(stopped)" in line for line in stopped
    )
    slow = lines(healthy(odom_receipts=[0.0, 0.5, 1.0, 1.5, 2.0, 2.5, 3.0], ended=3.1))
    assert any(line.startswith("warn odometry on /odom: 2.0 Hz") for line in slow), slow
    times = [k * 0.5 + i * 0.001 for k in range(6) for i in range(3)]  # 3 at a time, 2 Hz
    bursts = lines(healthy(odom_receipts=times, ended=2.6))
    warned = next(line for line in bursts if line.startswith("warn odometry on /odom: 6.8 Hz"))
    assert "in bursts of 3.0 (a new pose every 0.50 s)" in warned, warned
    assert "(new poses below 5 Hz)" in warned and "missions work up to 5 s late" in warned


def test_odometry_in_bursts_on_a_busy_link_is_named() -> None:
    """go2_ros2_sdk #231: three poses 1 ms apart every 0.176 s (17 Hz)."""
    times = [k * 0.176 + i * 0.001 for k in range(12) for i in range(3)]
    found = lines(healthy(odom_receipts=times, ended=times[-1] + 0.05))
    line = next(x for x in found if "odometry on /odom" in x)
    assert line.startswith("ok   odometry on /odom: 18.1 Hz") and "in bursts of 3.0" in line, line
    assert "a new pose every 0.18 s" in line


def test_without_twist_mux_velocity_goes_to_the_drivers_cmd_vel_out() -> None:
    obs = healthy()
    obs.subscribers["cmd_vel"], obs.publishers["cmd_vel_out"] = [], []
    found = lines(obs)
    assert (
        "ok   velocity goes to /cmd_vel_out: nothing relays /cmd_vel (nothing subscribes /cmd_vel)"
        in found
    )


def test_a_listener_on_cmd_vel_is_no_relay() -> None:
    """`ros2 topic echo /cmd_vel`, a recorder or a bridge on cmd_vel, and no twist_mux: the
    driver hears only cmd_vel_out (issue 23)."""
    obs = healthy()
    obs.subscribers["cmd_vel"], obs.publishers["cmd_vel_out"] = [Endpoint("/echo", TWIST_TYPE)], []
    found = lines(obs)
    assert (
        "ok   velocity goes to /cmd_vel_out: nothing relays /cmd_vel "
        "(subscribers of /cmd_vel: /echo)" in found
    ), found
    configured = lines(healthy(cmd_vel_topic="cmd_vel", subscribers=obs.subscribers))
    wanted = "fail velocity on /cmd_vel (configured) reaches no driver"
    assert any(line.startswith(wanted) for line in configured), configured


def test_a_namespaced_robot_is_told_twist_mux_does_not_reach_it() -> None:
    found = lines(healthy(namespace="robot0", subscribers={}, root_cmd_vel_subscribed=True))
    assert any("twist_mux listens on /cmd_vel, but it is not namespaced" in line for line in found)


def test_the_battery_source_is_reported() -> None:
    obs = healthy(battery_topic="battery", battery_levels=[0.42 * 100])
    obs.names["battery"] = "/battery"
    assert "ok   battery from /battery: 42%" in lines(obs)
    found = lines(healthy(battery_elsewhere=["/bms/battery"]))
    assert any("BatteryState seen on /bms/battery" in line for line in found)


def test_the_launch_without_its_driver_is_named() -> None:
    """robot.launch.py ran (twist_mux is up) but go2_driver_node died at start (issue 23)."""
    found = lines(
        healthy(
            nodes=[MUX, "/rviz2"],
            publishers={"cmd_vel_out": [Endpoint(MUX, TWIST_TYPE)]},
            subscribers={"cmd_vel": [Endpoint(MUX, TWIST_TYPE)]},
            odom_receipts=[],
            states=[],
        )
    )
    assert found[0].startswith("fail no go2_driver_node on the graph") and (
        "(/twist_mux, /rviz2 up: the launch ran, its driver did not)" in found[0]
    ), found[0]


def test_the_simulated_driver_counts_and_says_what_it_is() -> None:
    sim = "/shadowhound_sim_driver"
    obs = healthy(nodes=[sim, MUX])
    found = lines(obs)
    assert (
        "ok   driver: /shadowhound_sim_driver, ShadowHound's simulated driver (shadowhound "
        "sim-driver), not go2_ros2_sdk's go2_driver_node" in found
    ), found


def test_a_driver_of_another_name_serving_the_topics_is_a_warning() -> None:
    obs = healthy(nodes=["/my_go2_bridge"])
    obs.publishers["odom"] = [Endpoint("/my_go2_bridge", ODOM_TYPE)]
    obs.publishers["go2_states"] = [
        Endpoint("/my_go2_bridge", STATE_TYPE, UPSTREAM_HASHES[STATE_TYPE])
    ]
    obs.subscribers["webrtc_req"] = []
    found = lines(obs)
    assert found[0].startswith(
        "warn no go2_driver_node on the graph; /my_go2_bridge serves the driver's topics"
    ), found[0]


def test_a_namespaced_driver_node_counts() -> None:
    found = lines(healthy(nodes=["/robots/go2_driver_node"]))
    assert "ok   go2_ros2_sdk's driver: /robots/go2_driver_node" in found


def test_the_launch_is_recognised_by_the_names_robot_launch_py_gives_its_nodes() -> None:
    """go2_ros2_sdk's robot.launch.py names them go2_robot_state_publisher, go2_rviz2, ..."""
    found = lines(
        healthy(
            nodes=["/go2_robot_state_publisher", "/go2_rviz2", "/tts_node"],
            publishers={},
            subscribers={},
            odom_receipts=[],
            states=[],
        )
    )
    assert (
        "(/go2_robot_state_publisher, /go2_rviz2, /tts_node up: the launch ran, its driver "
        "did not)" in found[0]
    ), found[0]
