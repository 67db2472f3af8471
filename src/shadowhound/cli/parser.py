"""The `shadowhound` command line's arguments: every command, its options and their help (the
memory commands' are in memory.py, beside them).

Each command's handler lives in `missions` or `tools`; `main` (the package) dispatches.
"""

from __future__ import annotations

import argparse
from typing import Any, NoReturn

from .. import __version__
from ..config import available_profiles
from ..errors import UsageError
from ..mcp.limits import DEFAULT_IDLE_TIMEOUT, DEFAULT_MAX_SESSIONS
from ..robot_config import ROBOT_TYPES
from .memory import add_memory_commands


class Parser(argparse.ArgumentParser):
    """argparse that raises instead of exiting, so `run --json` can still answer in JSON."""

    def error(self, message: str) -> NoReturn:
        raise UsageError(f"{self.prog}: {message}", self.format_usage())


BACKENDS = ["offline", "openai", "ollama", "vllm", "llamacpp"]


def _robot_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--robot",
        choices=ROBOT_TYPES,
        default=None,
        help="robot to drive (default: the profile's, normally sim); go2 needs the 'ros' extra "
        "and go2_ros2_sdk's driver (or shadowhound sim-driver), with the profile's robot "
        "settings (robot: {type: go2, namespace: ...})",
    )


def _common(parser: argparse.ArgumentParser, suppress: bool, compare: bool = False) -> None:
    default: Any = argparse.SUPPRESS if suppress else None
    parser.add_argument(
        "--config",
        "-c",
        metavar="PROFILE|PATH",
        default=default,
        help="profile name ("
        + ", ".join(available_profiles())
        + ") or a YAML file; default $SHADOWHOUND_CONFIG or offline",
    )
    if compare:  # eval: several planners side by side
        parser.add_argument(
            "--backend",
            default=default,
            action="append",
            metavar="BACKEND[:OPTION...]",
            help="a planner to evaluate; repeat to compare several. BACKEND is "
            f"one of {', '.join(BACKENDS)}; OPTIONs: hybrid, llm (hybrid "
            "off), json_schema, plain, tools, react; e.g. --backend offline "
            "--backend llamacpp --backend llamacpp:llm:plain",
        )
    else:
        parser.add_argument(
            "--backend",
            default=default,
            choices=BACKENDS,
            help="planner backend; without --config it also picks that profile",
        )
    parser.add_argument("--model", default=default, help="language model name (llm.model)")
    parser.add_argument(
        "--base-url",
        default=default,
        metavar="URL",
        help="OpenAI-compatible endpoint, e.g. http://127.0.0.1:8000/v1",
    )
    parser.add_argument(
        "--mode",
        default=default,
        choices=["plan", "react"],
        help="language-model planning mode (llm.mode)",
    )
    parser.add_argument(
        "--time-scale",
        type=float,
        metavar="S",
        default=default,
        help="simulated robot: real seconds per simulated second (0 = fastest)",
    )
    parser.add_argument(
        "--verbose",
        "-v",
        action="count",
        default=argparse.SUPPRESS if suppress else 0,
        help="log more (-vv for debug)",
    )


def build_parser() -> argparse.ArgumentParser:
    parser = Parser(
        prog="shadowhound",
        description="Mission agent for quadruped robots: plans a sentence into checked skills "
        "and runs it on a simulated Unitree Go2 (default) or a real one.",
    )
    parser.add_argument("--version", action="version", version=f"shadowhound {__version__}")
    _common(parser, suppress=False)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    run = sub.add_parser(
        "run",
        help="plan and run one mission",
        description="Plan MISSION, check it, run it, print the result.",
    )
    _common(run, suppress=True)
    run.add_argument("mission", help='what to do, e.g. "stand up and walk forward 1 meter"')
    run.add_argument(
        "--json",
        action="store_true",
        help="print exactly one JSON object with the result on stdout",
    )
    run.add_argument("--quiet", "-q", action="store_true", help="no progress on stderr")
    run.add_argument(
        "--yes",
        action="store_true",
        help="approve plans that need approval (risky tricks) without asking",
    )
    run.add_argument(
        "--dry-run",
        action="store_true",
        help="plan and check only: show the plan and predicted path, move nothing",
    )

    skills = sub.add_parser("skills", help="list the skills with their argument schemas")
    _common(skills, suppress=True)
    skills.add_argument("--json", action="store_true", help="print the skills as JSON")

    chat = sub.add_parser("chat", help="talk to the agent (a REPL; /run MISSION runs one)")
    _common(chat, suppress=True)

    evaluate = sub.add_parser("eval", help="run mission cases from a YAML file and score them")
    _common(evaluate, suppress=True, compare=True)
    evaluate.add_argument("file", help="YAML list of {mission, expect} cases")
    evaluate.add_argument("--json", action="store_true", help="print the report as JSON")

    show = sub.add_parser("config", help="print the effective configuration (no secrets)")
    _common(show, suppress=True)

    doctor = sub.add_parser(
        "doctor",
        help="check the configuration, the backend and the model "
        "(and with --go2 the Go2 driver's ROS 2 link)",
    )
    _common(doctor, suppress=True)
    doctor.add_argument(
        "--go2",
        action="store_true",
        help="check the go2_ros2_sdk driver (also when the profile's robot is go2)",
    )
    doctor.add_argument("--namespace", default="", help="the robot's namespace, e.g. robot0")
    doctor.add_argument(
        "--cmd-vel-topic",
        default="",
        help="velocity topic to check ('' = as the robot discovers it)",
    )
    doctor.add_argument(
        "--battery-topic", default="", help="sensor_msgs/BatteryState topic ('' = none)"
    )
    doctor.add_argument(
        "--map-topic",
        default="map",
        help="nav_msgs/OccupancyGrid map whose frame TF must place (default map; '' = not checked)",
    )
    doctor.add_argument(
        "--coco-detections-topic",
        default="detected_objects",
        help="vision_msgs/Detection2DArray from the object detector (default detected_objects, "
        "go2_ros2_sdk's coco_detector; '' = not checked)",
    )
    doctor.add_argument(
        "--camera-info-topic",
        default="camera/camera_info",
        help="sensor_msgs/CameraInfo the detector's boxes need (default camera/camera_info)",
    )
    doctor.add_argument(
        "--speech-topic",
        default="/tts",
        help="std_msgs/String words to say, which go2_ros2_sdk's tts_node subscribes "
        "(default /tts; '' = not checked)",
    )
    doctor.add_argument(
        "--seconds", type=float, default=3.0, help="how long to watch the topics (default 3)"
    )

    add_memory_commands(sub, lambda p: _common(p, suppress=True))

    serve = sub.add_parser(
        "serve", help="run the web dashboard and HTTP API (needs the 'web' extra)"
    )
    _common(serve, suppress=True)
    _robot_option(serve)
    serve.add_argument(
        "--host",
        default="127.0.0.1",
        help="address to listen on; anything but a literal loopback address "
        "(127.x.x.x, ::1) or localhost needs a token",
    )
    serve.add_argument("--port", type=int, default=8080, help="TCP port (default 8080)")
    serve.add_argument(
        "--token",
        default=None,
        help="bearer token the API requires (default $SHADOWHOUND_TOKEN; the "
        "environment is safer: a command line is visible in ps)",
    )

    mcp = sub.add_parser(
        "mcp",
        help="run the MCP server for Claude Desktop and other MCP clients (needs the 'mcp' extra)",
        description="Serve ShadowHound's tools to MCP clients: over stdio "
        "(default; the client starts this command) or Streamable "
        "HTTP (--http).",
    )
    _common(mcp, suppress=True)
    _robot_option(mcp)
    mcp.add_argument(
        "--http",
        action="store_true",
        help="serve Streamable HTTP at http://HOST:PORT/mcp instead of stdio",
    )
    mcp.add_argument(
        "--host",
        default="127.0.0.1",
        help="HTTP address; anything but a literal loopback address needs a token",
    )
    mcp.add_argument("--port", type=int, default=8765, help="HTTP port (default 8765)")
    mcp.add_argument(
        "--token",
        default=None,
        help="bearer token HTTP clients must send (default $SHADOWHOUND_TOKEN)",
    )
    mcp.add_argument(
        "--allow-release-estop",
        action="store_true",
        help="offer the release_estop tool; each call asks the person through the client "
        "(MCP elicitation) and is refused when nobody can be asked or they decline. Without "
        "it no MCP client can release the e-stop",
    )
    mcp.add_argument(
        "--session-idle",
        type=float,
        default=DEFAULT_IDLE_TIMEOUT,
        metavar="SECONDS",
        help="HTTP: close a session after this long without a request in flight (default "
        f"{DEFAULT_IDLE_TIMEOUT:g}); a session whose client drops its connection closes at once",
    )
    mcp.add_argument(
        "--max-sessions",
        type=int,
        default=DEFAULT_MAX_SESSIONS,
        metavar="N",
        help=f"HTTP: at most N open sessions (default {DEFAULT_MAX_SESSIONS}); a new one "
        "closes the least recently used idle session, or is refused (503) while all are busy",
    )

    sub.add_parser(
        "node",
        help="run the ROS 2 MissionNode (needs the 'ros' extra): "
        "shadowhound node --ros-args -p name:=value ...",
        add_help=False,
    )
    sub.add_parser(
        "sim-driver",
        help="run a simulated Go2 behind go2_ros2_sdk's ROS 2 topics, "
        "behaving as the real driver does (for robot:=go2 without "
        "a robot): shadowhound sim-driver [options] [--ros-args "
        "...]; see shadowhound sim-driver --help",
        add_help=False,
    )
    _ros_clients(sub)
    return parser


def _ros_clients(sub: Any) -> None:
    """The commands that talk to running nodes over ROS 2, from the venv (no `ros2` command)."""
    send = sub.add_parser(
        "send",
        help="send a mission to a running `shadowhound node` over ROS 2 and follow it to its "
        "end (needs the 'ros' extra)",
        description="Send MISSION to the mission node on this ROS graph, by its execute_mission "
        "action when it offers one (else on mission_command), after DDS has matched both "
        "sides; show each step (the action's feedback) or status line on stderr and the "
        "node's response on stdout. Exit 0 when the mission succeeded, 1 when it failed or was "
        "refused (or --timeout passed: it is cancelled), 2 when no node answers, 130 when "
        "Ctrl-C cancelled it.",
    )
    send.add_argument("mission", help='what to do, e.g. "walk forward 1 meter"')
    send.add_argument(
        "--namespace",
        default="",
        help="the node's namespace (a node started with -r __ns:=/robot1: /robot1)",
    )
    send.add_argument(
        "--topic",
        action="store_true",
        help="publish on mission_command and follow mission_status instead of the action: "
        "the mission then waits behind a running one (the action refuses it) and cannot be "
        "cancelled from here",
    )
    send.add_argument(
        "--wait",
        type=float,
        default=10.0,
        metavar="S",
        help="seconds to wait for the node to be discovered (default 10)",
    )
    send.add_argument(
        "--timeout",
        type=float,
        default=0.0,
        metavar="S",
        help="cancel the mission and exit 1 when it has not ended after S seconds "
        "(default 0: wait for its end)",
    )
    send.add_argument("--quiet", "-q", action="store_true", help="no progress on stderr")

    estop = sub.add_parser(
        "estop",
        help="press the e-stop of every ShadowHound agent on this ROS graph (/shadowhound/estop), "
        "or --release it (needs the 'ros' extra)",
        description="Publish std_msgs/Empty on /shadowhound/estop (every agent stops at once and "
        "stays stopped) or /shadowhound/estop_release, once something subscribes, and wait "
        "until each subscriber has it. Exit 0 when delivered, 2 when nothing subscribes.",
    )
    estop.add_argument("--release", action="store_true", help="release the e-stop instead")
    estop.add_argument(
        "--wait",
        type=float,
        default=5.0,
        metavar="S",
        help="seconds to wait for a subscriber (default 5)",
    )

    fault = sub.add_parser(
        "sim-fault",
        help="set the faults of a running `shadowhound sim-driver` (sim_driver/fault), e.g. "
        """'{"odom": false}' (needs the 'ros' extra)""",
        description="Publish FAULT (a JSON object; {} clears every fault) on the simulated "
        "driver's sim_driver/fault; the keys are listed by shadowhound sim-driver --help and "
        "docs/go2.md. Exit 0 when the driver has it, 2 when no driver subscribes.",
    )
    fault.add_argument("fault", help="""a JSON object, e.g. '{"delay_ms": 200}'""")
    fault.add_argument(
        "--namespace", default="", help="the robot's namespace with several robots, e.g. robot0"
    )
    fault.add_argument(
        "--wait",
        type=float,
        default=5.0,
        metavar="S",
        help="seconds to wait for the driver (default 5)",
    )

    env = sub.add_parser(
        "loopback-env",
        help="print the environment that keeps ROS 2 traffic on this machine, for "
        'eval "$(shadowhound loopback-env)"',
        description="Print export lines: ROS_DOMAIN_ID, ROS_AUTOMATIC_DISCOVERY_RANGE=LOCALHOST, "
        "RMW_IMPLEMENTATION and the Fast DDS profile that allows only loopback and shared "
        "memory (the tests' settings). Use it in every terminal of a demo; not with a real "
        "robot on the network.",
    )
    env.add_argument(
        "--domain",
        type=int,
        default=None,
        metavar="N",
        help="ROS_DOMAIN_ID, 0..232 (default: 101 + your user id %% 100, the same in each of your "
        "terminals; not 0, which every ROS 2 process started without a domain joins)",
    )
