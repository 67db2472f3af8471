"""The node's e-stop is taken on a thread of its own: it reaches the robot while the node's
executor is stuck in another callback (a camera flood, a slow status publish, anything)."""

from __future__ import annotations

import threading

import pytest

from tests.ros.needs import require

require("rclpy")

import rclpy  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from std_msgs.msg import Empty  # noqa: E402

from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot  # noqa: E402
from shadowhound.ros.node import ESTOP_RELEASE_TOPIC, ESTOP_TOPIC, MissionNode  # noqa: E402
from tests.ros.rosclient import wait_until  # noqa: E402

pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


def test_estop_reaches_the_robot_while_the_node_executor_is_blocked() -> None:
    context = rclpy.Context()
    rclpy.init(context=context)
    settings = ShadowHoundConfig()
    robot = SimRobot(settings.sim, time_scale=1.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    node = MissionNode(agent, namespace="/lane", context=context)
    client = Node("lane_client", namespace="/lane", context=context)
    unblock, blocked = threading.Event(), threading.Event()

    def stuck() -> None:  # the executor's only thread waits here until the test lets it go
        blocked.set()
        unblock.wait(60)

    node.create_timer(0.01, stuck)
    executor = SingleThreadedExecutor(context=context)
    executor.add_node(node)
    spinner = threading.Thread(target=executor.spin, daemon=True)
    try:
        estop = client.create_publisher(Empty, ESTOP_TOPIC, RELIABLE)
        release = client.create_publisher(Empty, ESTOP_RELEASE_TOPIC, RELIABLE)
        wait_until(
            lambda: estop.get_subscription_count() and release.get_subscription_count(),
            30,
            "the e-stop subscriptions",
        )
        spinner.start()
        assert blocked.wait(10)
        estop.publish(Empty())
        wait_until(lambda: robot.get_state().estopped, 10, "the e-stop to reach the robot")
        assert agent.estop_latched and not unblock.is_set()  # while the executor is still stuck
        estop.publish(Empty())  # pressed twice, then released: handled in that order
        release.publish(Empty())
        wait_until(lambda: not robot.get_state().estopped, 10, "the release")
        assert [c.kind for c in robot.commands if c.kind.startswith("estop")][-3:] == [
            "estop",
            "estop",
            "estop_release",
        ]
    finally:
        unblock.set()
        node.shutdown()
        executor.shutdown(timeout_sec=2.0)
        spinner.join(5)
        node.destroy_node()
        client.destroy_node()
        rclpy.try_shutdown(context=context)
