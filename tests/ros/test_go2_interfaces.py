"""go2_interfaces as built here is go2_ros2_sdk's: the same type hashes as upstream's (else Fast
DDS matches the topic and silently drops every sample), and scripts/check_go2_interfaces.py
(which build_ros.sh uses to accept a sourced go2_ros2_sdk workspace) tells a wrong copy apart.
Skipped without rclpy or go2_interfaces unless SHADOWHOUND_REQUIRE_ROS=1 (then it fails)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

import pytest

from tests.ros.needs import require

require("rclpy", "go2_interfaces")

from go2_interfaces.msg import Go2State, WebRtcReq  # noqa: E402

from tests.ros.rosclient import ROOT, RosClient, wait_until  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")

# go2_ros2_sdk's go2_interfaces built on ROS 2 Jazzy (abizovnuralem/go2_ros2_sdk).
UPSTREAM = {
    "Go2State": "RIHS01_26947c9882eb8f10418057a5777d99d4b3163c30f479a5626f034a65c3ea2848",
    "WebRtcReq": "RIHS01_1b3c5ffa35c3257e84c4282ceef9f14148d3c51579ea5e359d76f720613261fd",
}
CHECK = ROOT / "scripts" / "check_go2_interfaces.py"


def built_hash(name: str) -> str:
    """From the type description rosidl installs beside the package (PREFIX/share/...)."""
    import go2_interfaces

    prefix = Path(go2_interfaces.__file__).resolve().parents[4]  # PREFIX/lib/pythonX/site-p..
    path = prefix / "share" / "go2_interfaces" / "msg" / f"{name}.json"
    hashes = json.loads(path.read_text())["type_hashes"]
    return next(h["hash_string"] for h in hashes if h["type_name"] == f"go2_interfaces/msg/{name}")


@pytest.mark.parametrize("name", sorted(UPSTREAM))
def test_the_built_type_hash_is_upstreams(name: str) -> None:
    assert built_hash(name) == UPSTREAM[name]


def test_dds_announces_upstreams_type_hashes() -> None:
    client = RosClient("shadowhound_go2_interfaces_test")
    try:
        for msg_type in (Go2State, WebRtcReq):
            topic = f"/hash_check/{msg_type.__name__.lower()}"
            client.publisher(msg_type, topic)
            info = wait_until(
                lambda t=topic: client.node.get_publishers_info_by_topic(t),
                10,
                f"the {topic} publisher in the graph",
            )
            assert str(info[0].topic_type_hash) == UPSTREAM[msg_type.__name__]
    finally:
        client.close()


def test_range_obstacle_carries_metres_as_floats() -> None:
    state = Go2State(range_obstacle=[0.25, 1.5, 2.75, 10.0])
    assert list(state.range_obstacle) == [0.25, 1.5, 2.75, 10.0]


def test_the_build_check_accepts_this_package_and_says_where_it_is() -> None:
    done = subprocess.run(
        [sys.executable, str(CHECK)], capture_output=True, text=True, timeout=60, cwd="/tmp"
    )
    assert done.returncode == 0, done.stderr
    assert Path(done.stdout.strip(), "msg").is_dir()


def test_the_build_check_refuses_a_copy_with_other_fields(tmp_path: Path) -> None:
    # A workspace whose go2_interfaces has our old, wrong Go2State (range_obstacle int16[4]).
    fields = dict(Go2State.get_fields_and_field_types(), range_obstacle="int16[4]")
    package = tmp_path / "go2_interfaces" / "msg"
    package.mkdir(parents=True)
    (package.parent / "__init__.py").write_text("")
    (package / "__init__.py").write_text(
        "class WebRtcReq:\n"
        f"    get_fields_and_field_types = staticmethod(lambda: "
        f"{WebRtcReq.get_fields_and_field_types()!r})\n"
        "class Go2State:\n"
        f"    get_fields_and_field_types = staticmethod(lambda: {fields!r})\n"
    )
    done = subprocess.run(
        [sys.executable, str(CHECK)],
        capture_output=True,
        text=True,
        timeout=60,
        cwd="/tmp",
        env={"PYTHONPATH": str(tmp_path), "HOME": os.environ["HOME"]},  # the test's home
    )
    assert done.returncode == 1
    assert (
        f"go2_interfaces at {tmp_path / 'go2_interfaces'} is not go2_ros2_sdk's: "
        "Go2State.range_obstacle is int16[4], go2_ros2_sdk's is float[4]"
    ) in done.stderr
