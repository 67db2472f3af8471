"""Go2 through go2_ros2_sdk's topics (issue 5): e-stop during a move to the driver's velocity zero.

Run:  .venv/bin/python bench/bench_go2.py [--runs N] [--write]
Needs rclpy, shadowhound_interfaces and go2_interfaces (bash scripts/build_ros.sh). DDS stays
on loopback (the project's Fast DDS profile, LOCALHOST discovery, a domain id from this pid).
--write replaces the "go2" section of bench/RESULTS.md with the figures measured now.

Method. The mission node runs as its own process (`shadowhound node --ros-args -p robot:=go2`),
as a user runs it. The simulated driver (`SimDriver`) runs in this process on its own executor
thread, with a SimRobot that stamps `time.perf_counter()` when its commanded velocity becomes
zero; a client node here publishes the mission and the e-stop. So the path timed on one clock
is: publish `/shadowhound/estop` -> DDS -> node process (executor, RobotAgent.estop,
Go2RosRobot.emergency_stop) -> zero Twist on `cmd_vel` -> DDS -> driver -> simulator. The
second figure runs on to the driver's odometry reporting the robot still (the simulator
brakes at its 1 m/s^2 limit from about 0.4 m/s).
"""

from __future__ import annotations

import argparse
import os
import platform
import random
import statistics
import subprocess
import sys
import tempfile
import threading
import time
from collections.abc import Callable
from datetime import date
from pathlib import Path
from typing import Any

from shadowhound.ros.dds import loopback_env

os.environ.update(loopback_env())  # before rclpy is imported

import rclpy  # noqa: E402
from nav_msgs.msg import Odometry  # noqa: E402
from rclpy.executors import SingleThreadedExecutor  # noqa: E402
from rclpy.logging import LoggingSeverity  # noqa: E402
from rclpy.node import Node  # noqa: E402
from rclpy.qos import QoSProfile, ReliabilityPolicy  # noqa: E402
from std_msgs.msg import Empty, String  # noqa: E402

from results import write_section  # noqa: E402
from shadowhound.config import SimConfig  # noqa: E402
from shadowhound.robot.sim import SimRobot  # noqa: E402
from shadowhound.ros.node import ESTOP_RELEASE_TOPIC, ESTOP_TOPIC  # noqa: E402
from shadowhound.ros.sim_driver import SimDriver  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
NS = "bench_go2"
RELIABLE = QoSProfile(depth=10, reliability=ReliabilityPolicy.RELIABLE)


class TimedSim(SimRobot):
    """A real-time SimRobot that stamps when its commanded velocity becomes zero."""

    def __init__(self) -> None:
        super().__init__(SimConfig(time_scale=1.0), name="bench-sim")
        self.zeroed: float | None = None

    def send_velocity(self, vx: float, vy: float, wz: float) -> None:
        super().send_velocity(vx, vy, wz)
        if not (vx or vy or wz) and self.zeroed is None:
            self.zeroed = time.perf_counter()

    def stop(self) -> None:
        super().stop()
        if self.zeroed is None:
            self.zeroed = time.perf_counter()


def wait(predicate: Callable[[], Any], timeout: float, what: str) -> Any:
    deadline = time.monotonic() + timeout
    while not (value := predicate()):
        if time.monotonic() > deadline:
            raise SystemExit(f"bench_go2: timed out waiting for {what}")
        time.sleep(0.0005)
    return value


def percentiles(values: list[float]) -> dict[str, float]:
    ordered = sorted(values)
    p99 = ordered[min(len(ordered) - 1, round(0.99 * (len(ordered) - 1)))]
    return {"p50": statistics.median(ordered), "p99": p99, "max": ordered[-1],
            "n": len(ordered)}


def bench_estop(runs: int) -> dict[str, dict[str, float]]:
    sim = TimedSim()
    driver = SimDriver(sim, namespace=f"/{NS}")
    driver.get_logger().set_level(LoggingSeverity.WARN)
    client = Node("bench_go2_client")
    status: list[str] = []
    still: list[float] = []  # perf_counter of odometry messages reporting the robot still
    client.create_subscription(String, "/mission_status", lambda m: status.append(m.data),
                               RELIABLE)
    client.create_subscription(
        Odometry, f"/{NS}/odom",
        lambda m: still.append(time.perf_counter()) if abs(m.twist.twist.linear.x) < 1e-3
        else None, 10)
    connected: list[bool] = []
    client.create_subscription(String, "/shadowhound/robot_status",
                               lambda m: connected.append('"connected":true' in m.data), 10)
    missions = client.create_publisher(String, "/mission_command", RELIABLE)
    estop = client.create_publisher(Empty, ESTOP_TOPIC, RELIABLE)
    release = client.create_publisher(Empty, ESTOP_RELEASE_TOPIC, RELIABLE)
    executors = [SingleThreadedExecutor(), SingleThreadedExecutor()]
    executors[0].add_node(driver)
    executors[1].add_node(client)
    threads = [threading.Thread(target=e.spin, daemon=True) for e in executors]
    for thread in threads:
        thread.start()
    log = Path(tempfile.gettempdir()) / f"bench_go2_node_{os.getpid()}.log"
    with log.open("w") as out:  # the node's output, for when a run times out
        node = subprocess.Popen([sys.executable, "-m", "shadowhound", "node", "--ros-args",
                                 "-p", "robot:=go2", "-p", f"robot_namespace:={NS}"],
                                stdout=out, stderr=subprocess.STDOUT, cwd=ROOT)
    to_zero: list[float] = []
    to_still: list[float] = []
    try:
        wait(lambda: missions.get_subscription_count() and estop.get_subscription_count(), 60,
             "the mission node")
        wait(lambda: connected and connected[-1], 30, "the node's Go2 robot to see odometry")
        for _ in range(runs):
            sim.reset()
            mark = len(status)
            missions.publish(String(data="walk forward 2 meters"))
            wait(lambda: sim.get_state().vx > 0.1, 10, "the robot to walk")
            time.sleep(random.uniform(0.0, 0.1))  # the e-stop lands anywhere in the stride
            sim.zeroed = None
            t0 = time.perf_counter()
            estop.publish(Empty())
            to_zero.append(wait(lambda: sim.zeroed, 5, "the driver's velocity zero") - t0)
            to_still.append(wait(lambda s=t0: next((t for t in still if t > s), None), 5,
                                 "odometry reporting the robot still") - t0)
            wait(lambda m=mark: any(s.startswith(("FAILED", "COMPLETED"))
                                    for s in status[m:]), 10, "the mission to end")
            release.publish(Empty())
            time.sleep(0.05)  # let the release land before the next mission
    finally:
        node.terminate()
        node.wait(15)
        for executor in executors:
            executor.shutdown(timeout_sec=2.0)
        driver.close()
        driver.destroy_node()
        client.destroy_node()
    return {"zero": percentiles(to_zero), "still": percentiles(to_still)}


def ms(value: float) -> str:
    return f"{value * 1000:.1f} ms"


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--runs", type=int, default=30)
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    args = parser.parse_args()
    rclpy.init()
    try:
        figures = bench_estop(args.runs)
    finally:
        rclpy.try_shutdown()
    zero, still = figures["zero"], figures["still"]
    rows = [
        f"| `/shadowhound/estop` publish to the driver's commanded velocity zero (node process -> "
        f"`cmd_vel` -> `shadowhound sim-driver`), robot walking | p99 < 100 ms | "
        f"{ms(zero['p50'])} | {ms(zero['p99'])} | {ms(zero['max'])} | {zero['n']} |",
        f"| same, to the driver's odometry reporting the robot still (braking at 1 m/s^2) | - | "
        f"{ms(still['p50'])} | {ms(still['p99'])} | {ms(still['max'])} | {still['n']} |",
    ]
    section = "\n".join([
        "<!-- go2:start -->",
        "## Go2 through go2_ros2_sdk's topics (issue 5, `bench/bench_go2.py`)",
        "",
        f"Measured {date.today().isoformat()} with `python bench/bench_go2.py --write` "
        f"(CPython {platform.python_version()}, {platform.machine()}, {os.cpu_count()} cores; "
        "ROS 2 Jazzy rclpy from PyPI, Fast DDS on shared memory / loopback).",
        "",
        "| what | target | p50 | p99 | max | runs |",
        "|---|---|---|---|---|---|",
        *rows,
        "",
        "How: `shadowhound node --ros-args -p robot:=go2` runs as its own process; the simulated "
        "driver runs in the benchmark process with a SimRobot that stamps `time.perf_counter()` "
        "when its commanded velocity becomes zero, and a client node there publishes the "
        "mission (\"walk forward 2 meters\") and, 0-100 ms after the robot reaches 0.1 m/s, the "
        "e-stop. Both stamps are on the benchmark's clock; the path crosses DDS twice (e-stop "
        "in, zero Twist out).",
        "<!-- go2:end -->",
    ])
    print(section)
    if args.write:
        write_section("go2", section)
    return 0


if __name__ == "__main__":
    sys.exit(main())
