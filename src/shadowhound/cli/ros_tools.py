"""Commands for ROS 2: the entry points `node` and `sim-driver`, and, from the virtual
environment without the `ros2` command, `send` (a mission to a running node, followed to its
end), `estop` (press or release every agent's e-stop), `sim-fault` (a fault of the simulated
driver) and `loopback-env` (the environment that keeps a demo's DDS on this machine)."""

from __future__ import annotations

import argparse
import json
import math
import os
import shlex
import sys
import time
from typing import TYPE_CHECKING

from ..config import ShadowHoundConfig
from ..errors import NodeNotFound
from ..exit_codes import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE

# What a command that needs ROS 2 tells a Python without it (said once, for every such command).
ROS_INSTALL = "pip install 'shadowhound[ros]' (Python 3.11 or 3.12) and bash scripts/build_ros.sh"
CANCEL_WAIT = 10.0  # seconds to wait for a cancelled mission's end

if TYPE_CHECKING:
    from ..ros.client import Mission, MissionUpdate


def needs_ros(what: str, exc: ImportError) -> int:
    """Say on stderr that `what` needs the `ros` extra and how to install it; exit code 2."""
    print(f"shadowhound: {what} needs ROS 2 ({ROS_INSTALL}): {exc}", file=sys.stderr)
    return EXIT_USAGE


def cmd_node(ros_argv: list[str]) -> int:
    try:
        from ..ros.node import main as node_main
    except ImportError as exc:
        return needs_ros("the ROS 2 node (rclpy and shadowhound_interfaces)", exc)
    return node_main(ros_argv)


def cmd_sim_driver(argv: list[str]) -> int:
    try:
        from ..sim_driver.driver import main as driver_main
    except ImportError as exc:
        return needs_ros("the simulated Go2 driver (rclpy and go2_interfaces)", exc)
    return driver_main(argv)


# -- send ----------------------------------------------------------------------------------


def cmd_send(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    """Send a mission to the node and follow it: progress on stderr, the response on stdout;
    exit 0 when it succeeded, 1 when it failed (or --timeout passed), 130 after Ctrl-C."""
    try:
        from ..ros.client import NodeClient
    except ImportError as exc:
        return needs_ros("shadowhound send", exc)
    client = NodeClient(args.namespace)
    try:
        try:
            mission = client.send(args.mission, args.wait, use_topic=args.topic)
        except NodeNotFound as exc:
            print(f"shadowhound send: {exc}", file=sys.stderr)
            return EXIT_USAGE
        return _follow(mission, args)
    finally:
        client.close()


def _follow(mission: Mission, args: argparse.Namespace) -> int:
    """Show what is seen of `mission` until it ends. Ctrl-C, or --timeout passing, cancels it
    (a mission sent on the topic cannot be cancelled: then the command ends at once)."""
    from ..ros.client import ACTION, MISSION_TOPIC, MissionEnd, where

    say = _Progress(args.quiet)
    target = ACTION if mission.via == "action" else MISSION_TOPIC
    say(f"mission: {args.mission!r} -> {where(args.namespace, target)} ({mission.via})")
    give_up_at = time.monotonic() + args.timeout if args.timeout else math.inf
    stopped = 0  # the exit code once a cancel was asked for: 130 Ctrl-C, 1 --timeout
    while True:
        try:
            update = mission.next(0.1)
        except KeyboardInterrupt:
            if stopped or not _cancel(mission, "interrupted"):
                return EXIT_INTERRUPTED
            stopped, give_up_at = EXIT_INTERRUPTED, time.monotonic() + CANCEL_WAIT
            continue
        if isinstance(update, MissionEnd):
            print(update.response, flush=True)
            return stopped or (EXIT_OK if update.success else EXIT_FAILED)
        if update is not None:
            say.update(update)
        elif time.monotonic() > give_up_at:
            if stopped:
                print(
                    f"shadowhound send: no answer to the cancel within {CANCEL_WAIT:g} s",
                    file=sys.stderr,
                )
                return stopped
            if not _cancel(mission, f"no end after {args.timeout:g} s (--timeout)"):
                return EXIT_FAILED
            stopped, give_up_at = EXIT_FAILED, time.monotonic() + CANCEL_WAIT


def _cancel(mission: Mission, why: str) -> bool:
    """Cancel `mission` and say so; False (said too) when it went by topic and cannot be."""
    if mission.cancel():
        print(f"shadowhound send: {why}: cancelling the mission (the robot stops)", file=sys.stderr)
        return True
    print(
        f"shadowhound send: {why}; a mission sent on the topic cannot be cancelled and may "
        "still run (shadowhound estop stops every robot)",
        file=sys.stderr,
    )
    return False


class _Progress:
    """What `send` shows on stderr of a mission (nothing with --quiet)."""

    def __init__(self, quiet: bool) -> None:
        self.quiet = quiet

    def __call__(self, text: str) -> None:
        if not self.quiet:
            print(text, file=sys.stderr, flush=True)

    def update(self, update: MissionUpdate) -> None:
        from ..ros.client import PlanSeen, StatusSeen, StepSeen

        if isinstance(update, PlanSeen):
            self(f"plan: {update.steps} step(s)")
        elif isinstance(update, StepSeen):
            done = f"done ({100 * update.progress:.0f}% of the mission)"
            said = done if update.finished else "..."
            self(f"  [{update.index}/{update.count}] {update.skill} {said}")
        elif isinstance(update, StatusSeen):
            self(f"status: {update.text}")


# -- estop, sim-fault ----------------------------------------------------------------------


def cmd_estop(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    """Publish on /shadowhound/estop (or estop_release) once subscribed, and say who got it."""
    try:
        from ..robot_config import ESTOP_RELEASE_TOPIC, ESTOP_TOPIC
        from ..ros.client import NodeClient
    except ImportError as exc:
        return needs_ros("shadowhound estop", exc)
    client = NodeClient()
    try:
        count = client.estop(args.release, args.wait)
    except NodeNotFound as exc:
        print(f"shadowhound estop: {exc}", file=sys.stderr)
        return EXIT_USAGE
    finally:
        client.close()
    if args.release:
        print(f"e-stop released: {count} subscriber(s) of {ESTOP_RELEASE_TOPIC} got it")
    else:
        print(
            f"e-stop pressed: {count} subscriber(s) of {ESTOP_TOPIC} got it; every agent on "
            "this ROS graph stops and stays stopped until `shadowhound estop --release`"
        )
    return EXIT_OK


def cmd_sim_fault(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    """Publish a fault (JSON) on the simulated driver's sim_driver/fault."""
    try:
        fault = json.loads(args.fault)
    except json.JSONDecodeError as exc:
        fault, problem = None, f"not JSON ({exc})"
    else:
        problem = "" if isinstance(fault, dict) else f"a JSON {type(fault).__name__}"
    if problem:
        print(
            f"shadowhound sim-fault: {args.fault!r} is {problem}; give a JSON object such as "
            """'{"odom": false}' (see shadowhound sim-driver --help)""",
            file=sys.stderr,
        )
        return EXIT_USAGE
    try:
        from std_msgs.msg import String

        from ..ros.client import NodeClient, where
    except ImportError as exc:
        return needs_ros("shadowhound sim-fault", exc)
    topic = where(args.namespace, "sim_driver/fault")
    client = NodeClient()
    try:
        client.publish(topic, String(data=json.dumps(fault)), args.wait)
    except NodeNotFound as exc:
        print(f"shadowhound sim-fault: {exc}", file=sys.stderr)
        return EXIT_USAGE
    finally:
        client.close()
    print(f"fault set on {topic}: {json.dumps(fault)}")
    return EXIT_OK


# -- loopback-env --------------------------------------------------------------------------


def cmd_loopback_env(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    """Print `export` lines for `eval`: the loopback DDS settings the tests use."""
    from ..ros.dds import loopback_env

    domain = args.domain if args.domain is not None else default_domain()
    try:
        env = loopback_env(domain)
    except ValueError as exc:
        print(f"shadowhound loopback-env: {exc}", file=sys.stderr)
        return EXIT_USAGE
    print(f"# ROS 2 traffic on this machine only, in domain {domain} (not 0: see docs/go2.md)")
    for key, value in env.items():
        print(f"export {key}={shlex.quote(value)}")
    return EXIT_OK


def default_domain() -> int:
    """A domain of this user's own, the same in each of their terminals: 101 + uid % 100 (the
    tests take 1..100).

    Not 0, the default of every ROS 2 process: anything else on this machine started without a
    domain (a robot's driver, another demo) would share the graph and its topics.
    """
    return 101 + os.getuid() % 100 if hasattr(os, "getuid") else 142
