"""The go2 robot's and the simulated driver's parameters. Pure Python: runs without rclpy."""

from __future__ import annotations

import math

import pytest

from shadowhound.robot.go2.motion import GO2_MOTION
from shadowhound.ros.params import ParameterError, parse_parameters
from shadowhound.sim_driver.options import DriverSettings, build_parser, parse_settings


def test_go2_is_accepted_with_its_topics_and_namespace() -> None:
    settings = parse_parameters(
        {
            "robot": "go2",
            "robot_namespace": "robot0",
            "odom_topic": "/robot0/odom",
            "odom_timeout": 1,
        }
    )
    assert settings.go2_options() == {
        "namespace": "robot0",
        "cmd_vel_topic": "",
        "webrtc_topic": "webrtc_req",
        "odom_topic": "/robot0/odom",
        "state_topic": "go2_states",
        "odom_timeout": 1.0,
        "odom_latency": None,
        "battery_topic": "",
        "detections_topic": "",
        "detector_classes": (),
        "coco_detections_topic": "",
        "camera_info_topic": "camera/camera_info",
        "camera_x": 0.3,
        "camera_y": 0.0,
        "camera_yaw": 0.0,
        "coco_max_range": 6.0,
        "firmware_tricks": False,
        "map_topic": "map",
        "scan_topic": "scan",
        "nav2_action": "navigate_to_pose",
        "speech_topic": "/tts",
        "map_frame": "map",
    }


def test_a_coco_detector_its_camera_and_its_range_are_checked() -> None:
    settings = parse_parameters(
        {
            "robot": "go2",
            "coco_detections_topic": "detected_objects",
            "camera_x": 0.33,
            "camera_yaw": 0.1,
            "coco_max_range": 4,
        }
    )
    options = settings.go2_options()
    assert options["coco_detections_topic"] == "detected_objects"
    assert (options["camera_x"], options["camera_y"], options["camera_yaw"]) == (0.33, 0.0, 0.1)
    assert options["coco_max_range"] == 4.0
    with pytest.raises(ParameterError) as info:
        parse_parameters(
            {"coco_detections_topic": "9bad", "camera_y": 5.0, "coco_max_range": math.inf}
        )
    text = str(info.value)
    assert "coco_detections_topic '9bad' is not a valid ROS topic name" in text
    assert "camera_y must be a number in -2..2, got 5.0" in text
    assert "coco_max_range must be a number in 0.5..30, got inf" in text


def test_go2_options_for_latency_battery_and_firmware_tricks_are_checked() -> None:
    settings = parse_parameters(
        {
            "robot": "go2",
            "odom_latency": 0.3,
            "battery_topic": "battery_state",
            "go2_firmware_tricks": True,
            "cmd_vel_topic": "cmd_vel_out",
            "detections_topic": "detections",
        }
    )
    options = settings.go2_options()
    assert options["detections_topic"] == "detections"
    assert (
        options["odom_latency"],
        options["battery_topic"],
        options["firmware_tricks"],
        options["cmd_vel_topic"],
    ) == (0.3, "battery_state", True, "cmd_vel_out")
    with pytest.raises(ParameterError) as info:
        parse_parameters(
            {"odom_latency": 5.5, "battery_topic": "9bad", "detections_topic": "bad topic"}
        )
    assert "odom_latency must be -1 (measured) or seconds in 0..5, got 5.5" in str(info.value)
    assert "battery_topic '9bad' is not a valid ROS topic name" in str(info.value)
    assert "detections_topic 'bad topic' is not a valid ROS topic name" in str(info.value)


def test_go2_gets_motion_settings_for_real_odometry_unless_the_profile_sets_them(
    monkeypatch: pytest.MonkeyPatch,
) -> None:
    sim = parse_parameters({"robot": "sim"}).agent_settings().motion
    assert sim.position_tolerance == 0.002 and sim.control_rate_hz == 20.0
    go2 = parse_parameters({"robot": "go2"}).agent_settings().motion
    assert go2.position_tolerance == 0.02 and go2.control_rate_hz == 10.0
    assert math.isclose(go2.yaw_tolerance, math.radians(0.5)) and GO2_MOTION
    monkeypatch.setenv("SHADOWHOUND_MOTION__POSITION_TOLERANCE", "0.05")
    chosen = parse_parameters({"robot": "go2"}).agent_settings().motion
    assert chosen.position_tolerance == 0.05 and chosen.control_rate_hz == 10.0


def test_driver_settings_default_and_are_checked_all_at_once() -> None:
    assert parse_settings({}) == DriverSettings()
    assert DriverSettings().battery is None and DriverSettings().relay is True
    chosen = parse_settings({"camera_rate_hz": 0, "odom_rate_hz": 10, "battery": 80})
    assert (chosen.odom_rate_hz, chosen.battery) == (10.0, 80.0)
    assert DriverSettings().detector == "shadowhound"
    assert parse_settings({"detector": "coco"}).detector == "coco"
    with pytest.raises(ParameterError) as info:
        parse_settings(
            {
                "odom_rate_hz": 0.0,
                "camera_width": 2.5,
                "move_timeout": True,
                "battery": 120,
                "battery_topic": "1bad",
                "lidar": 1,
                "start_posture": "kneeling",
                "detector": "yolo",
            }
        )
    message = str(info.value)
    for part in (
        "odom_rate_hz must be in 1..200, got 0.0",
        "camera_width must be an integer, got float 2.5",
        "move_timeout must be a number, got bool True",
        "battery must be in 0..100, got 120",
        "battery_topic '1bad' is not a valid ROS topic name",
        "unknown setting(s) lidar",
        "start_posture must be one of standing, sitting, lying, got 'kneeling'",
        "detector must be one of shadowhound, coco, none, got 'yolo'",
    ):
        assert part in message


def test_every_driver_setting_has_a_command_line_option() -> None:
    parser = build_parser("sim-driver", "", "")
    assert vars(parser.parse_args([])) == {}  # only given options override ROS parameters
    given = vars(
        parser.parse_args(
            [
                "--battery",
                "42.5",
                "--no-relay",
                "--robots",
                "2",
                "--odom-delay",
                "0.5",
                "--battery-topic",
                "bat",
            ]
        )
    )
    assert given == {
        "battery": 42.5,
        "relay": False,
        "robots": 2,
        "odom_delay": 0.5,
        "battery_topic": "bat",
    }
    text = parser.format_help()
    for name in DriverSettings.__dataclass_fields__:
        assert "--" + name.replace("_", "-") in text


def test_slam_settings_of_the_node_and_the_driver_are_checked() -> None:
    assert parse_parameters({"robot": "go2"}).go2_options()["map_frame"] == "map"
    assert parse_parameters({"map_frame": ""}).go2_options()["map_frame"] == ""
    with pytest.raises(ParameterError, match="map_frame '9 map' is not a frame id"):
        parse_parameters({"map_frame": "9 map"})
    chosen = parse_settings({"slam": True, "odom_drift": 0.05})
    assert (chosen.slam, chosen.odom_drift) == (True, 0.05)
    with pytest.raises(ParameterError) as info:
        parse_settings({"slam": True, "robots": 2, "odom_drift": 0.9})
    assert "slam is for one robot" in str(info.value)
    assert "odom_drift must be in 0..0.5, got 0.9" in str(info.value)


def test_a_slam_error_fault_is_read_and_shown_like_a_jump() -> None:
    from shadowhound.sim_driver.faults import Faults

    faults = Faults.from_json('{"slam_error": {"x": 0.5, "yaw_deg": 90}}')
    assert faults.slam_error == (0.5, 0.0, math.pi / 2)
    assert faults.to_dict()["slam_error"] == {"x": 0.5, "y": 0.0, "yaw_deg": 90.0}
    assert not faults.lies  # it takes effect at once, not after a distance
    with pytest.raises(ValueError, match='slam_error must be an object {"x": m'):
        Faults.from_json('{"slam_error": [0.5, 0]}')


def test_a_go2_edu_takes_the_namespace_parameter() -> None:
    settings = parse_parameters({"robot": "go2_edu", "robot_namespace": "edu"}).agent_settings()
    assert settings.robot.type == "go2_edu" and settings.robot.namespace == "edu"
    plain = parse_parameters({"robot": "go2_edu"}).agent_settings()
    assert plain.robot.type == "go2_edu" and plain.robot.namespace == ""
