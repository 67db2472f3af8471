"""The command line at its edges, as users meet them in a shell: a real `shadowhound` process
without the `ros` extra."""

from __future__ import annotations

import os
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from tests.test_cli import shadowhound

# -- without the `ros` extra ---------------------------------------------------------------------

# Installed in front of every other importer, this makes the interpreter answer for rclpy (and
# the message packages) exactly as one without the `ros` extra does: ModuleNotFoundError.
_NO_ROS = """
import importlib.abc
import sys

ROS = {"rclpy", "std_msgs", "go2_interfaces", "shadowhound_interfaces", "nav_msgs"}


class _NotInstalled(importlib.abc.MetaPathFinder):
    def find_spec(self, name, path=None, target=None):
        if name.split(".")[0] in ROS:
            raise ModuleNotFoundError(f"No module named {name!r}", name=name)
        return None


sys.meta_path.insert(0, _NotInstalled())
"""


@pytest.fixture
def no_ros(tmp_path: Path) -> dict[str, str]:
    """The environment of a Python without the `ros` extra (a sitecustomize hides it)."""
    site = tmp_path / "no_ros"
    site.mkdir()
    (site / "sitecustomize.py").write_text(textwrap.dedent(_NO_ROS))
    paths = [str(site), *filter(None, os.environ.get("PYTHONPATH", "").split(os.pathsep))]
    return {"PYTHONPATH": os.pathsep.join(paths)}


def test_the_no_ros_python_really_lacks_rclpy(no_ros):
    full = {**os.environ, **no_ros}
    proc = subprocess.run(
        [sys.executable, "-c", "import rclpy"], capture_output=True, text=True, env=full
    )
    assert proc.returncode == 1 and "No module named 'rclpy'" in proc.stderr


def test_doctor_go2_without_the_ros_extra_says_what_to_install(no_ros):
    proc = shadowhound("doctor", "--go2", "--seconds", "0.1", env=no_ros)
    assert proc.returncode == 2, proc.stdout + proc.stderr
    assert "internal error" not in proc.stderr and "Traceback" not in proc.stderr
    assert "pip install 'shadowhound[ros]'" in proc.stdout
    assert "scripts/build_ros.sh" in proc.stdout
    assert "No module named 'rclpy'" in proc.stdout


def test_doctor_go2_names_the_robot_it_checks(no_ros):
    """The header says the Go2 is checked, also when the profile's robot is the simulator."""
    proc = shadowhound("doctor", "--go2", "--seconds", "0.1", env=no_ros)
    header = proc.stdout.splitlines()[0]
    assert "robot 'go2'" in header and "robot 'sim'" not in header, header
    plain = shadowhound("doctor")
    assert plain.returncode == 0 and "robot 'sim'" in plain.stdout.splitlines()[0]
