"""Fixtures for the whole suite, and its homes (see tests/home.py)."""

from __future__ import annotations

import os
import shutil
import tempfile
from collections.abc import Iterator
from pathlib import Path

import pytest

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
from tests.home import RealHome, home_env

_real_home: RealHome | None = None
_session_home: Path | None = None


def pytest_configure(config: pytest.Config) -> None:
    """Before any test module is imported: this process (and every process it starts, xdist
    workers included) lives in a temporary home; what outlives a test (module-scoped node
    processes, servers) keeps this one."""
    global _real_home, _session_home
    if not hasattr(config, "workerinput"):  # the controller (or the only process)
        _real_home = RealHome.record(Path.home())
        # xdist workers derive their ROS domains from the run's pid (tests/ros/conftest.py).
        os.environ["SHADOWHOUND_TESTS_RUN_PID"] = str(os.getpid())
    _session_home = Path(tempfile.mkdtemp(prefix="shadowhound-test-home-"))
    os.environ.update(home_env(_session_home))


def pytest_unconfigure(config: pytest.Config) -> None:
    if _session_home is not None:
        shutil.rmtree(_session_home, ignore_errors=True)


def pytest_sessionfinish(session: pytest.Session, exitstatus: int) -> None:
    """The suite must leave the user's home as it found it: checked once, after every test
    (and every xdist worker) has finished; a change fails the run."""
    if _real_home is None:
        return
    changed = _real_home.changes()
    if changed:
        reporter = session.config.pluginmanager.get_plugin("terminalreporter")
        lines = [
            f"the tests changed the real home {_real_home.path} (or, on a shared machine, "
            "another program did meanwhile):",
            *changed[:50],
        ]
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
def agent(robot: SimRobot, settings: ShadowHoundConfig) -> Iterator[RobotAgent]:
    a = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    a.initialize()
    yield a
    a.cleanup()


@pytest.fixture(autouse=True)
def own_home(tmp_path_factory: pytest.TempPathFactory, monkeypatch: pytest.MonkeyPatch) -> Path:
    """Every test runs in an empty home of its own (HOME, the XDG directories, the memory's
    data_dir), also for the processes it starts: nothing one test or run remembers reaches
    another, and nothing reaches the user's home."""
    path = tmp_path_factory.mktemp("home")
    for name, value in home_env(path).items():
        monkeypatch.setenv(name, value)
    return path
