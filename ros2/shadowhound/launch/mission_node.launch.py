"""Launch the ShadowHound mission agent: ros2 launch shadowhound mission_node.launch.py
backend_config:=ollama camera_topic:=/camera/compressed

With a Go2 through go2_ros2_sdk: ros2 launch shadowhound mission_node.launch.py robot:=go2

(Not exercised in ShadowHound's own tests: launch and launch_ros are not on PyPI. The tests run
the same node through its entry point, `shadowhound node --ros-args ...`.)
"""

from launch import LaunchDescription
from launch.actions import DeclareLaunchArgument
from launch.substitutions import LaunchConfiguration
from launch_ros.actions import Node

ARGUMENTS = {
    "backend_config": "offline",
    "robot": "sim",
    "time_scale": "1.0",
    "camera_topic": "/camera/image_raw",
    "camera_type": "auto",
    "mission_topic": "mission_command",
    "status_topic": "mission_status",
    "robot_status_topic": "/shadowhound/robot_status",
    "diagnostics_topic": "/shadowhound/diagnostics",
    "web_interface_port": "8080",
    "enable_web_ui": "false",
    "robot_namespace": "",
    "robot_name": "",
    "cmd_vel_topic": "",
    "webrtc_topic": "webrtc_req",
    "odom_topic": "odom",
    "go2_states_topic": "go2_states",
    "odom_timeout": "0.5",
    "odom_latency": "-1.0",
    "battery_topic": "",
    "detections_topic": "",
    "detector_classes": "",
    "coco_detections_topic": "",
    "camera_info_topic": "camera/camera_info",
    "camera_x": "0.3",
    "camera_y": "0.0",
    "camera_yaw": "0.0",
    "coco_max_range": "6.0",
    "go2_firmware_tricks": "false",
    "navigation": "",
    "map_topic": "map",
    "scan_topic": "scan",
    "nav2_action": "navigate_to_pose",
    "speech_topic": "/tts",
    "map_frame": "map",
}


def generate_launch_description() -> LaunchDescription:
    declared = [
        DeclareLaunchArgument(name, default_value=default) for name, default in ARGUMENTS.items()
    ]
    node = Node(
        package="shadowhound",
        executable="mission_node",
        name="shadowhound_mission_agent",
        output="screen",
        emulate_tty=True,
        parameters=[{name: LaunchConfiguration(name) for name in ARGUMENTS}],
    )
    return LaunchDescription([*declared, node])
