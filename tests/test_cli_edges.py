"""The command line at its edges, as users meet them in a shell: a real `shadowhound` process
without the `ros` extra, writing into a pipe that closes, given a mission without quotes, or
asked to serve on a port something else holds."""

from __future__ import annotations

import json
import os
import socket
import subprocess
import sys
import textwrap
from pathlib import Path

import pytest

from tests.test_cli import shadowhound

DATA = Path(__file__).parent / "data"

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


@pytest.mark.parametrize(
    "args",
    [("send", "stand up"), ("estop",), ("estop", "--release"), ("sim-fault", "{}")],
    ids=" ".join,
)
def test_ros_clients_without_the_ros_extra_say_what_to_install(args, no_ros):
    proc = shadowhound(*args, env=no_ros)
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr and "internal error" not in proc.stderr
    assert f"shadowhound: shadowhound {args[0]} needs ROS 2 (pip install 'shadowhound[ros]'" in (
        proc.stderr
    )


def test_loopback_env_is_for_eval_and_not_domain_0():
    script = (
        'eval "$("$1" -m shadowhound loopback-env --domain 42)"; env | grep -E "^(ROS|RMW|FAST)"'
    )
    proc = subprocess.run(
        ["bash", "-c", script, "bash", sys.executable], capture_output=True, text=True, timeout=60
    )
    env = dict(line.split("=", 1) for line in proc.stdout.splitlines())
    assert env["ROS_DOMAIN_ID"] == "42" and env["ROS_AUTOMATIC_DISCOVERY_RANGE"] == "LOCALHOST"
    assert Path(env["FASTRTPS_DEFAULT_PROFILES_FILE"]).name == "fastdds_loopback.xml"
    default = shadowhound("loopback-env").stdout
    domain = default.split("export ROS_DOMAIN_ID=")[1].split()[0]
    assert 0 < int(domain) <= 232
    assert shadowhound("loopback-env", "--domain", "300").returncode == 2


def test_doctor_go2_names_the_robot_it_checks(no_ros):
    """The header says the Go2 is checked, also when the profile's robot is the simulator."""
    proc = shadowhound("doctor", "--go2", "--seconds", "0.1", env=no_ros)
    header = proc.stdout.splitlines()[0]
    assert "robot 'go2'" in header and "robot 'sim'" not in header, header
    plain = shadowhound("doctor")
    assert plain.returncode == 0 and "robot 'sim'" in plain.stdout.splitlines()[0]


# -- a pipe that closes ----------------------------------------------------------------------


def into_closed_pipe(
    *args: str, env: dict[str, str] | None = None, stdin: str = ""
) -> subprocess.CompletedProcess:
    """Run `shadowhound ARGS` with stdout a pipe whose reading end is closed before it writes
    a byte: every write fails, as into `| head -1` once head has gone."""
    read, write = os.pipe()
    os.close(read)
    full = {**os.environ, **(env or {})}
    full.pop("SHADOWHOUND_CONFIG", None)
    try:
        return subprocess.run(
            [sys.executable, "-m", "shadowhound", *args],
            input=stdin,
            stdout=write,
            stderr=subprocess.PIPE,
            text=True,
            timeout=60,
            env=full,
        )
    finally:
        os.close(write)


@pytest.fixture(scope="module")
def history(tmp_path_factory) -> dict[str, str]:
    """A data directory whose history holds one mission (and the objects it saw)."""
    env = {"SHADOWHOUND_MEMORY__DATA_DIR": str(tmp_path_factory.mktemp("history"))}
    assert shadowhound("run", "-q", "what do you see?", env=env).returncode == 0
    return env


@pytest.mark.parametrize(
    "args",
    [
        ("skills",),
        ("skills", "--json"),
        ("history",),
        ("history", "--json"),
        ("places",),
        ("places", "--json"),
        ("recall", "ball"),
        ("config",),
        ("doctor",),
        ("run", "stand up"),
        ("run", "--json", "stand up"),
        ("run", "--dry-run", "walk forward 1 meter"),
        ("eval", str(DATA / "missions_public.yaml")),
        ("eval", "--json", str(DATA / "missions_public.yaml")),
    ],
    ids=" ".join,
)
def test_a_closed_pipe_ends_quietly_with_141(args, history):
    proc = into_closed_pipe(*args, env=history)
    assert "Traceback" not in proc.stderr and "BrokenPipe" not in proc.stderr, proc.stderr
    assert "internal error" not in proc.stderr and "Exception ignored" not in proc.stderr
    assert proc.returncode == 141, proc.stderr  # 128 + SIGPIPE, as the shell reports for cat


@pytest.mark.parametrize(
    "lines", ["where are you?\n", "/run walk forward 1 meter\n", "/estop\nwhere are you?\n"]
)
def test_chat_into_a_closed_pipe_ends_quietly_with_141(lines):
    proc = into_closed_pipe("chat", stdin=lines)
    assert "Traceback" not in proc.stderr and "Exception" not in proc.stderr, proc.stderr
    assert proc.returncode == 141, proc.stderr  # the steps of /run are on stderr, still open


@pytest.mark.parametrize("args", [("--help",), ("run", "--help")])
def test_help_into_a_closed_pipe_is_quiet(args):
    """argparse itself ignores a failed write of its help (and exits 0)."""
    proc = into_closed_pipe(*args)
    assert proc.stderr == "" and proc.returncode in (0, 141)


@pytest.mark.parametrize("command", ["skills", "history"])
def test_head_takes_the_first_line_and_nothing_is_said(command, history):
    """The shell pipe of the report: `shadowhound skills | head -1`."""
    full = {**os.environ, **history}
    full.pop("SHADOWHOUND_CONFIG", None)
    proc = subprocess.run(
        [
            "bash",
            "-c",
            f'"$1" -m shadowhound {command} | head -1; echo "exit ${{PIPESTATUS[0]}}"',
            "bash",
            sys.executable,
        ],
        capture_output=True,
        text=True,
        timeout=60,
        env=full,
    )
    first, status = proc.stdout.splitlines()
    assert first and status in ("exit 0", "exit 141"), proc.stdout  # 0: it all fit the pipe
    assert proc.stderr == "", proc.stderr


# -- a mission without quotes, a port in use ----------------------------------------------------


def test_a_mission_without_quotes_is_answered_with_the_quoted_command():
    proc = shadowhound("run", "walk", "forward", "1", "meter")
    assert proc.returncode == 2
    assert "unrecognized arguments" not in proc.stderr
    assert "put it in quotes" in proc.stderr
    assert "shadowhound run 'walk forward 1 meter'" in proc.stderr, proc.stderr
    assert "Traceback" not in proc.stderr


def test_the_quoted_command_keeps_the_options_given():
    proc = shadowhound("--time-scale", "0", "run", "-q", "walk", "forward", "--yes", "1", "m")
    assert proc.returncode == 2
    assert "shadowhound --time-scale 0 run -q 'walk forward' --yes '1 m'" not in proc.stderr
    assert "shadowhound --time-scale 0 run -q 'walk forward 1 m' --yes" in proc.stderr, proc.stderr


def test_a_mission_without_quotes_with_json_is_one_json_error():
    proc = shadowhound("run", "--json", "turn", "left")
    assert proc.returncode == 2
    answer = json.loads(proc.stdout)
    assert (
        answer["error_kind"] == "usage" and "shadowhound run --json 'turn left'" in answer["error"]
    )


def test_an_unknown_option_is_still_named():
    proc = shadowhound("run", "--bogus", "stand up")
    assert proc.returncode == 2 and "unrecognized arguments: --bogus" in proc.stderr


@pytest.fixture
def taken_port():
    """A loopback port another program listens on."""
    with socket.socket() as sock:
        sock.bind(("127.0.0.1", 0))
        sock.listen(1)
        yield sock.getsockname()[1]


@pytest.mark.parametrize("command", [("serve",), ("mcp", "--http")], ids=" ".join)
def test_serving_on_a_taken_port_suggests_another(command, taken_port):
    proc = shadowhound(*command, "--port", str(taken_port))
    assert proc.returncode == 2, proc.stderr
    assert "Traceback" not in proc.stderr
    assert f"port {taken_port}" in proc.stderr and "in use" in proc.stderr, proc.stderr
    suggested = proc.stderr.split(f"shadowhound {' '.join(command)} --port ")[1].split()[0]
    with socket.socket() as sock:  # the port suggested is free
        sock.bind(("127.0.0.1", int(suggested)))
