from __future__ import annotations

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot


@pytest.fixture
def settings() -> ShadowHoundConfig:
    return ShadowHoundConfig()


@pytest.fixture
def robot(settings: ShadowHoundConfig) -> SimRobot:
    return SimRobot(settings.sim, time_scale=0.0)


@pytest.fixture
def agent(robot: SimRobot, settings: ShadowHoundConfig) -> RobotAgent:
    a = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    a.initialize()
    yield a
    a.cleanup()
