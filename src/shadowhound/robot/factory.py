"""make_robot: the one place a robot's name becomes a robot.

The profile names the backend and holds its settings (`robot: {type: go2, namespace: robot0}`,
config.RobotSettings); the agent, the ROS node, the web server, the MCP server and the CLI all
build their robot here. A backend's code is imported only when it is chosen, so the simulator
never pulls in rclpy.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import TYPE_CHECKING, Any

from ..errors import ConfigError, RobotError

if TYPE_CHECKING:
    from ..config import ShadowHoundConfig
    from ..robot_config import RobotSettings
    from .base import Robot, TrickInfo

__all__ = ["make_robot", "tricks_of"]


def tricks_of(choice: RobotSettings) -> Mapping[str, TrickInfo]:
    """The tricks the backend `choice` will perform (its robot's `tricks`), known before it is
    built: the skills it is offered (`body.sport`) are set from them."""
    from .go2 import api as go2_api  # pure data: no ROS

    if choice.type == "sim":
        return go2_api.offered(ai_mode=True)  # the simulated Go2 performs every one
    if choice.type == "go2":
        return go2_api.offered(ai_mode=choice.firmware_tricks)
    if choice.type == "go2_edu":
        return go2_api.offered(ai_mode=False)
    raise ConfigError(f"no robot backend {choice.type!r}")


def make_robot(settings: ShadowHoundConfig, *, context: Any = None) -> Robot:
    """The robot `settings.robot` chooses, built with its settings. `context`: the rclpy
    context a ROS backend joins (None: the running one, else a private one). Raises
    ConfigError naming what is missing when the backend cannot be built."""
    choice = settings.robot
    if choice.type == "sim":
        from .sim.robot import SimRobot

        return SimRobot(settings.sim)
    if choice.type == "go2":
        try:
            from .go2.robot import Go2RosRobot
        except ImportError as exc:
            raise ConfigError(
                "robot go2 needs rclpy and the go2_interfaces package (the 'ros' extra; source "
                f"your go2_ros2_sdk workspace or run scripts/build_ros.sh): {exc}"
            ) from exc
        try:
            return Go2RosRobot(choice, context=context)
        except RobotError as exc:
            raise ConfigError(f"robot go2: {exc}") from exc
    if choice.type == "go2_edu":
        try:
            from .go2_edu.robot import Go2EduRobot
        except ImportError as exc:
            raise ConfigError(
                "robot go2_edu needs rclpy and the unitree_api and unitree_go packages (the "
                "'ros' extra; source your unitree_ros2 workspace or run scripts/build_ros.sh): "
                f"{exc}"
            ) from exc
        try:
            return Go2EduRobot(choice, context=context)
        except RobotError as exc:
            raise ConfigError(f"robot go2_edu: {exc}") from exc
    raise ConfigError(f"no robot backend {choice.type!r}")  # the settings' union forbids it
