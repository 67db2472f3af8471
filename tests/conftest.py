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


@pytest.fixture(autouse=True, scope="session")
def _memory_in_a_temporary_directory(tmp_path_factory):
    """Profiles keep history in ~/.shadowhound; tests (and the CLI processes they start) must
    not touch the developer's real history."""
    import os

    os.environ["SHADOWHOUND_MEMORY__DATA_DIR"] = str(tmp_path_factory.mktemp("memory"))
    yield
