"""Commands that inspect or serve: `skills`, `config`, `doctor`, `serve`, `mcp` (the memory
commands are in memory, the ROS 2 commands in ros_tools)."""

from __future__ import annotations

import argparse
import errno
import json
import sys
from typing import Any

from .. import jsonout
from ..config import ShadowHoundConfig
from ..exit_codes import EXIT_FAILED, EXIT_OK, EXIT_USAGE
from .ros_tools import ROS_INSTALL

# -- skills ----------------------------------------------------------------------------------


def cmd_skills(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    from ..robot.factory import tricks_of
    from ..skills import default_registry

    # The skills of the robot the profile chooses (its tricks are its own).
    described = default_registry(tricks_of(settings.robot)).describe()
    if args.json:
        jsonout.dump(described, sys.stdout, indent=2)
        sys.stdout.write("\n")
        return EXIT_OK
    for skill in described:
        props = skill["parameters"].get("properties", {})
        required = set(skill["parameters"].get("required", []))
        params = ", ".join(f"{n}{'' if n in required else '?'}" for n in props)
        print(f"{skill['name']}({params})")
        print(f"    {skill['description']}")
        for name, prop in props.items():
            print(f"      {name}: {_schema_summary(prop)}")
    return EXIT_OK


def _schema_summary(prop: dict[str, Any]) -> str:
    options = prop.get("anyOf", [prop])
    kinds = [o.get("type", "any") for o in options if o.get("type") != "null"]
    text = "|".join(kinds) or "any"
    if "enum" in prop or any("enum" in o for o in options):
        enum = prop.get("enum") or next(o["enum"] for o in options if "enum" in o)
        text += " one of " + ", ".join(map(str, enum))
    for key, sign in (
        ("minimum", ">="),
        ("exclusiveMinimum", ">"),
        ("maximum", "<="),
        ("exclusiveMaximum", "<"),
    ):
        bound = next((o[key] for o in options if key in o), None)
        if bound is not None:
            text += f" {sign}{bound:g}"
    if prop.get("description"):
        text += f" - {prop['description']}"
    return text


# -- config --------------------------------------------------------------------------------------


def cmd_config(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    import yaml

    sys.stdout.write(yaml.safe_dump(json.loads(settings.model_dump_json()), sort_keys=False))
    return EXIT_OK


# -- doctor --------------------------------------------------------------------------------------


def cmd_doctor(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    go2 = args.go2 or settings.robot.type == "go2"
    robot = repr(settings.robot.type)
    if (
        go2 and settings.robot.type != "go2"
    ):  # the Go2 is what is checked, whatever the profile says
        robot = f"'go2' (--go2; the profile's robot is {robot})"
    print(
        f"ok  configuration: profile {settings.profile!r}, backend {settings.backend!r}, "
        f"robot {robot}"
    )
    s = settings.safety
    print(
        f"ok  safety limits: {s.max_linear_speed:g} m/s, {s.max_angular_speed:g} rad/s, "
        f"{s.max_step_distance:g} m per step, geofence {s.geofence_radius:g} m "
        f"(margin {s.geofence_margin:g} m), risky tricks "
        f"{'allowed' if s.allow_risky_tricks else 'refused'}"
    )
    if settings.backend == "offline":
        print("ok  planner: offline rules (no network, no model)")
    else:
        from ..llm import LLMBackend

        for line in LLMBackend(settings.backend, settings.llm).check():
            print(f"ok  {line}")
        print(
            f"ok  planning mode {settings.llm.mode!r}, plan format "
            f"{settings.llm.plan_format!r}, vision {'on' if settings.llm.vision else 'off'}"
        )
    if go2:
        return _doctor_go2(args)
    _doctor_places(settings)
    return EXIT_OK


def _doctor_places(settings: ShadowHoundConfig) -> None:
    """The profile's places on the simulator's map, from the origin: each one the body can
    reach, or why not (a place inside an object's clearance is reached at the nearest point
    that keeps the body clear)."""
    from ..robot.sim.robot import SimRobot
    from ..world import place_problem

    belief = SimRobot(settings.sim, time_scale=0.0).belief()
    if belief is None or not settings.places:
        return
    problems = {
        name: why
        for name, point in settings.places.items()
        if (why := place_problem(belief, (0.0, 0.0), point))
    }
    good = [name for name in settings.places if name not in problems]
    if good:
        print(f"ok  places reachable on the simulator's map: {', '.join(good)}")
    for name, why in problems.items():
        print(f"warn place {name!r} {settings.places[name]} cannot be reached: {why}")


def _doctor_go2(args: argparse.Namespace) -> int:
    """The Go2 driver's link, in words (see ros/go2_doctor.py, ros/go2_doctor_watch.py)."""
    try:
        from ..ros.go2_doctor import diagnose
        from ..ros.go2_doctor_watch import observe, require_ros

        require_ros()
    except ImportError as exc:
        print(
            f"fail Go2 checks need ROS 2 (rclpy) and go2_interfaces: {exc}\n"
            f"     fix: {ROS_INSTALL}; or source ROS 2 and your go2_ros2_sdk workspace"
        )
        return EXIT_USAGE
    print(f"...  watching the Go2 driver's and its stack's topics for {args.seconds:g} s")
    findings = diagnose(
        observe(
            args.namespace,
            seconds=args.seconds,
            cmd_vel_topic=args.cmd_vel_topic,
            battery_topic=args.battery_topic,
            coco_detections_topic=args.coco_detections_topic,
            camera_info_topic=args.camera_info_topic,
            speech_topic=args.speech_topic,
            map_topic=args.map_topic,
        )
    )
    for finding in findings:
        print(finding)
    return EXIT_FAILED if any(f.level == "fail" for f in findings) else EXIT_OK


# -- serve ---------------------------------------------------------------------------------------


def cmd_serve(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    try:
        from ..web import serve_main
    except ImportError as exc:
        print(
            f"shadowhound: the web dashboard needs the 'web' extra "
            f"(pip install 'shadowhound[web]'): {exc}",
            file=sys.stderr,
        )
        return EXIT_USAGE
    taken = _port_taken(args.host, args.port, "shadowhound serve")
    if taken:
        print(taken, file=sys.stderr)
        return EXIT_USAGE
    return int(serve_main(settings, args.host, args.port, args.token))


def _port_taken(host: str, port: int, command: str) -> str:
    """Why `command` cannot listen on `host`:`port` because another program does, with a free
    port to use instead; "" when the port is free (or fails otherwise: the server says why)."""
    if not _in_use(host, port):
        return ""
    why = f"{command}: port {port} on {host} is in use by another program"
    if port == 8080:
        why += " (llama.cpp's server, for one, listens on 8080 too)"
    return f"{why}; choose another port: {command} --port {_free_port(host, port + 1)}"


def _free_port(host: str, start: int) -> int:
    """The first free port from `start` on (of the next hundred), else one the system picks."""
    from ..serving import bind

    free = (p for p in range(start, min(start + 100, 65536)) if not _in_use(host, p))
    found = next(free, 0)
    if not found:
        with bind(host, 0) as sock:
            found = sock.getsockname()[1]
    return found


def _in_use(host: str, port: int) -> bool:
    from ..errors import ServeError
    from ..serving import bind

    try:
        bind(host, port).close()
    except ServeError as exc:
        return isinstance(exc.__cause__, OSError) and exc.__cause__.errno == errno.EADDRINUSE
    return False


# -- mcp -----------------------------------------------------------------------------------------


def cmd_mcp(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    from ..mcp import main as mcp_main

    taken = _port_taken(args.host, args.port, "shadowhound mcp --http") if args.http else ""
    if taken:
        print(taken, file=sys.stderr)
        return EXIT_USAGE

    return int(
        mcp_main(
            settings,
            http=args.http,
            host=args.host,
            port=args.port,
            token=args.token,
            allow_release_estop=args.allow_release_estop,
            session_idle=args.session_idle,
            max_sessions=args.max_sessions,
        )
    )
