"""What another robot saw never steers a Go2, over real DDS (issue 32, item 3), judged by the
simulated driver's ground truth.

As a new user would: `shadowhound run "go to the chair"` on the simulator, then, from the same
home (the same history database), `shadowhound sim-driver` (no detector) and `shadowhound node
-p robot:=go2`, and "go to the chair" to the node. The Go2 cannot see the chair and never saw it;
the simulator's sighting is not its own: it is refused, saying whose sighting it is, and the
truth shows the robot did not move. A place the Go2 is taught is its own: it walks there.

Skipped without rclpy or the interface packages unless SHADOWHOUND_REQUIRE_ROS=1.
"""

from __future__ import annotations

import math
import os
import subprocess
import sys
from collections.abc import Iterator

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces", "nav2_msgs")

from tests.ros.rosclient import ROOT, RosClient  # noqa: E402
from tests.ros.test_go2_truth import start_rig  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


@pytest.fixture(scope="module")
def client() -> Iterator[RosClient]:
    c = RosClient("shadowhound_go2_memory_client")
    yield c
    c.close()


def on_the_simulator(*args: str) -> subprocess.CompletedProcess[str]:
    """`shadowhound ARGS` with the offline profile's simulator, in this test's home."""
    env = {k: v for k, v in os.environ.items() if k != "SHADOWHOUND_CONFIG"}
    return subprocess.run(
        [sys.executable, "-m", "shadowhound", *args],
        capture_output=True,
        text=True,
        timeout=180,
        env=env,
        cwd=ROOT,
    )


def test_the_simulators_chair_is_no_goal_for_a_go2_from_the_same_home(client: RosClient) -> None:
    went = on_the_simulator("run", "go to the chair")
    assert went.returncode == 0 and "reached the yellow chair" in went.stdout, went
    rig, stop = start_rig(client, (), "/memory", "/memory", "memory")
    try:
        start = rig.truth.still()
        final = rig.agent.run("go to the chair", 90.0)
        end = rig.truth.still()
        assert final.startswith("FAILED: "), (final, rig.node.output()[-3000:])
        assert "The yellow chair was seen by robot 'sim', not by this robot: not a goal" in final
        assert "remembered from an earlier mission" not in final
        assert math.dist((start["x"], start["y"]), (end["x"], end["y"])) < 0.05, (start, end)
        # Its own memory is a goal: a place taught to it, walked to, by the truth.
        taught = rig.agent.run("walk forward 1 meter, remember this spot as the mat", 90.0)
        assert taught.startswith("COMPLETED: "), taught
        mat = rig.truth.still()
        assert rig.agent.run("walk backward 1 meter", 90.0).startswith("COMPLETED: ")
        back = rig.agent.run("go to the mat", 90.0)
        end = rig.truth.still()
        assert back.startswith("COMPLETED: "), back
        # Through the driver's Nav2 (navigation auto), as the Go2 Nav2 tests judge a goal.
        assert math.dist((mat["x"], mat["y"]), (end["x"], end["y"])) < 0.10, (mat, end)
    finally:
        stop()
    # The simulator's listing shows the Go2's place as history, labelled, never a goal.
    listed = on_the_simulator("places")
    assert "taught to other robots (history, never goals for robot 'sim'):" in listed.stdout
    assert any(
        line.split()[:1] == ["mat"] and line.endswith("taught to go2:memory")
        for line in listed.stdout.splitlines()
    ), listed.stdout
