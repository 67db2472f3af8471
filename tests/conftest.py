from __future__ import annotations

from pathlib import Path

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from tests.home import RealHome

_real_home: RealHome | None = None


def pytest_configure(config: pytest.Config) -> None:
    global _real_home
    if not hasattr(config, "workerinput"):  # the controller (or the only process)
        _real_home = RealHome.record(Path.home())


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """The suite must leave the user's home as it found it: checked once, after every test
    (and every xdist worker) has finished; a change fails the run."""
    if _real_home is None:
        return
    changed = _real_home.changes()
    if changed:
        reporter = session.config.pluginmanager.get_plugin("terminalreporter")
        lines = [f"the tests changed the real home {_real_home.path}:", *changed[:50]]
        if reporter is not None:
            reporter.ensure_newline()
            reporter.write_sep("=", "real home changed", red=True)
            reporter.write_line("\n".join(lines))
        session.exitstatus = pytest.ExitCode.TESTS_FAILED


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
