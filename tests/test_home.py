"""Each test runs in an empty home of its own, its child processes too, and the user's home is
left alone (tests/home.py; the real home is checked once more after the whole suite)."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

from shadowhound import load_config
from tests.home import RealHome, home_env


def test_each_test_has_an_empty_home_of_its_own(own_home: Path) -> None:
    assert Path.home() == own_home and Path("~").expanduser() == own_home
    assert list(own_home.iterdir()) == []
    for name, value in home_env(own_home).items():
        assert os.environ[name] == value
    (own_home / "left-behind").write_text("a test's leftovers")


def test_no_test_sees_what_another_left_in_its_home(own_home: Path) -> None:
    assert not (own_home / "left-behind").exists() and list(own_home.iterdir()) == []


def test_child_processes_live_in_the_tests_home(own_home: Path) -> None:
    code = "import pathlib; print(pathlib.Path.home())"
    done = subprocess.run(
        [sys.executable, "-c", code], capture_output=True, text=True, check=True, timeout=60
    )
    assert done.stdout.strip() == str(own_home)


def test_profiles_keep_their_memory_in_the_tests_home(own_home: Path) -> None:
    """`memory.data_dir: ~/.shadowhound` in every profile, with and without the environment."""
    from_env = load_config("offline").memory.data_dir
    assert Path(from_env).expanduser() == own_home / ".shadowhound"
    from_profile = load_config("offline", environ={}).memory
    assert from_profile.enabled
    assert Path(from_profile.data_dir).expanduser() == own_home / ".shadowhound"


def test_the_real_home_check_sees_what_a_run_would_leave(tmp_path: Path) -> None:
    user = tmp_path / "user"
    (user / ".shadowhound").mkdir(parents=True)
    (user / ".config" / "chromium").mkdir(parents=True)
    (user / ".shadowhound" / "history.db").write_bytes(b"old")
    real = RealHome.record(user)
    assert real.changes() == []
    (user / ".config" / "chromium" / "Local State").write_text("{}")  # the user's browser
    assert real.changes() == []
    (user / ".shadowhound" / "history.db").write_bytes(b"old and new")
    (user / ".mcp-inspector").mkdir()
    assert real.changes() == ["created .mcp-inspector", "modified .shadowhound/history.db"]
