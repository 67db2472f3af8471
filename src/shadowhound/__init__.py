"""ShadowHound: a mission agent for quadruped robots.

    from shadowhound import RobotAgent, SimRobot
    agent = RobotAgent()            # offline planner, simulated Go2
    result = agent.execute_mission("stand up and walk forward 1 meter")
    print(result.success, result.response, result.robot)

Importing this package loads no ROS, web, vector-store or model library.
"""

from __future__ import annotations

from .agent import MissionExecutor, MissionExecutorConfig, RobotAgent, RobotAgentConfig
from .config import ShadowHoundConfig, load_config
from .errors import ConfigError, ShadowHoundError
from .events import MissionEvent
from .plan import Plan, PlanningError, SkillCall, Usage
from .result import MissionResult, MissionStatus, StepResult, StepStatus, Timing
from .robot.base import Robot, RobotError
from .robot.sim.robot import MockRobot, SimRobot
from .skills import Skill, SkillRegistry, SkillValidationError, default_registry
from .state import CameraFrame, Pose2D, Posture, RobotState

__version__ = "0.1.0"

__all__ = [
    "CameraFrame",
    "ConfigError",
    "MissionEvent",
    "MissionExecutor",
    "MissionExecutorConfig",
    "MissionResult",
    "MissionStatus",
    "MockRobot",
    "Plan",
    "PlanningError",
    "Pose2D",
    "Posture",
    "Robot",
    "RobotAgent",
    "RobotAgentConfig",
    "RobotError",
    "RobotState",
    "ShadowHoundConfig",
    "ShadowHoundError",
    "SimRobot",
    "Skill",
    "SkillCall",
    "SkillRegistry",
    "SkillValidationError",
    "StepResult",
    "StepStatus",
    "Timing",
    "Usage",
    "__version__",
    "default_registry",
    "load_config",
]
