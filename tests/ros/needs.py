"""Module-level guard for tests that need ROS 2: skip without it, unless CI requires it."""

from __future__ import annotations

import importlib.util
import os

import pytest


def require(*modules: str) -> None:
    """Skip the calling test module when a module is missing; with SHADOWHOUND_REQUIRE_ROS=1
    (the main CI run) fail instead, so a broken ROS install cannot pass as skipped tests."""
    missing = [m for m in modules if importlib.util.find_spec(m) is None]
    if not missing:
        return
    why = (
        f"ROS 2 tests need {' and '.join(missing)}: install the 'ros' extra and run "
        "bash scripts/build_ros.sh"
    )
    if os.environ.get("SHADOWHOUND_REQUIRE_ROS") == "1":
        raise RuntimeError(why)
    pytest.skip(why, allow_module_level=True)
