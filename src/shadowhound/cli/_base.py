"""What every command shares: exit codes and building an agent from settings."""

from __future__ import annotations

from typing import Any

from ..config import ShadowHoundConfig

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


def make_agent(settings: ShadowHoundConfig) -> Any:
    """An initialized agent (raises ConfigError, e.g. an unreachable backend)."""
    from ..agent import RobotAgent

    agent = RobotAgent(settings)
    agent.initialize()
    return agent
