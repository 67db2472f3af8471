"""`shadowhound`: run missions, list skills, chat, and evaluate mission cases.

Exit codes: 0 success, 1 mission (or evaluation) failure, 2 usage or configuration error,
130 interrupted (the robot is stopped first).
"""

from __future__ import annotations

import argparse
import json
import logging
import sys
import threading
import time
from collections.abc import Sequence
from typing import Any, TextIO

from . import __version__
from . import events as ev
from .config import ConfigError, ShadowHoundConfig, available_profiles, load_config
from .memory.history import MemoryStoreError

EXIT_OK, EXIT_FAILED, EXIT_USAGE, EXIT_INTERRUPTED = 0, 1, 2, 130


def _common(parser: argparse.ArgumentParser, suppress: bool) -> None:
    default: Any = argparse.SUPPRESS if suppress else None
    parser.add_argument("--config", "-c", metavar="PROFILE|PATH", default=default,
                        help="profile name (" + ", ".join(available_profiles()) +
                        ") or a YAML file; default $SHADOWHOUND_CONFIG or offline")
    parser.add_argument("--backend", default=default,
                        choices=["offline", "openai", "ollama", "vllm", "llamacpp"],
                        help="planner backend; without --config it also picks that profile")
    parser.add_argument("--model", default=default, help="language model name (llm.model)")
    parser.add_argument("--base-url", default=default, metavar="URL",
                        help="OpenAI-compatible endpoint, e.g. http://127.0.0.1:8000/v1")
    parser.add_argument("--mode", default=default, choices=["plan", "react"],
                        help="language-model planning mode (llm.mode)")
    parser.add_argument("--time-scale", type=float, metavar="S", default=default,
                        help="simulated robot: real seconds per simulated second (0 = fastest)")
    parser.add_argument("--verbose", "-v", action="count", default=argparse.SUPPRESS
                        if suppress else 0, help="log more (-vv for debug)")


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="shadowhound",
        description="Mission agent for quadruped robots: plans a sentence into checked skills "
                    "and runs it on a simulated Unitree Go2 (default) or a real one.",
    )
    parser.add_argument("--version", action="version", version=f"shadowhound {__version__}")
    _common(parser, suppress=False)
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    run = sub.add_parser("run", help="plan and run one mission",
                         description="Plan MISSION, check it, run it, print the result.")
    _common(run, suppress=True)
    run.add_argument("mission", help='what to do, e.g. "stand up and walk forward 1 meter"')
    run.add_argument("--json", action="store_true",
                     help="print exactly one JSON object with the result on stdout")
    run.add_argument("--quiet", "-q", action="store_true", help="no progress on stderr")
    run.add_argument("--yes", action="store_true",
                     help="approve plans that need approval (risky tricks) without asking")
    run.add_argument("--dry-run", action="store_true",
                     help="plan and check only: show the plan and predicted path, move nothing")

    skills = sub.add_parser("skills", help="list the skills with their argument schemas")
    _common(skills, suppress=True)
    skills.add_argument("--json", action="store_true", help="print the skills as JSON")

    chat = sub.add_parser("chat", help="talk to the agent (a REPL; /run MISSION runs one)")
    _common(chat, suppress=True)

    evaluate = sub.add_parser("eval", help="run mission cases from a YAML file and score them")
    _common(evaluate, suppress=True)
    evaluate.add_argument("file", help="YAML list of {mission, expect} cases")
    evaluate.add_argument("--json", action="store_true", help="print the report as JSON")

    show = sub.add_parser("config", help="print the effective configuration (no secrets)")
    _common(show, suppress=True)

    doctor = sub.add_parser("doctor", help="check the configuration, the backend and the model")
    _common(doctor, suppress=True)

    history = sub.add_parser("history", help="list past missions, or show one (memory.enabled)")
    _common(history, suppress=True)
    history.add_argument("mission_id", nargs="?", help="show this mission in full")
    history.add_argument("--limit", type=int, default=20, help="how many to list (default 20)")
    history.add_argument("--json", action="store_true", help="print JSON")

    places = sub.add_parser("places", help="list the known places, or forget a taught one")
    _common(places, suppress=True)
    places.add_argument("--forget", metavar="NAME", help="forget a taught place")
    places.add_argument("--json", action="store_true", help="print JSON")

    recall = sub.add_parser("recall", help="search retrieval memory (memory.enable_rag)")
    _common(recall, suppress=True)
    recall.add_argument("query", help="what to look for, e.g. 'where is the fridge?'")

    serve = sub.add_parser("serve", help="run the web dashboard and HTTP API (needs the 'web' "
                                         "extra)")
    _common(serve, suppress=True)
    serve.add_argument("--host", default="127.0.0.1",
                       help="address to listen on; anything but loopback needs a token")
    serve.add_argument("--port", type=int, default=8080, help="TCP port (default 8080)")
    serve.add_argument("--token", default=None,
                       help="bearer token the API requires (default $SHADOWHOUND_TOKEN; the "
                            "environment is safer: a command line is visible in ps)")

    sub.add_parser("node", help="run the ROS 2 MissionNode (needs the 'ros' extra): "
                                "shadowhound node --ros-args -p name:=value ...",
                   add_help=False)
    sub.add_parser("sim-driver", help="run a simulated Go2 with go2_ros2_sdk's ROS 2 topics "
                                      "(for robot:=go2 without a robot): shadowhound sim-driver "
                                      "--ros-args ...", add_help=False)
    return parser


def _settings(args: argparse.Namespace) -> ShadowHoundConfig:
    overrides: dict[str, Any] = {}
    profile = args.config
    if args.backend:
        overrides["backend"] = args.backend
        if profile is None and args.backend in available_profiles():
            profile = args.backend  # --backend ollama alone means the ollama profile
    if args.time_scale is not None:
        overrides["sim"] = {"time_scale": args.time_scale}
    llm = {k: v for k, v in (("model", args.model), ("base_url", args.base_url),
                             ("mode", args.mode)) if v is not None}
    if llm:
        overrides["llm"] = llm
    return load_config(profile, overrides)


def _agent(settings: ShadowHoundConfig) -> Any:
    from .agent import RobotAgent

    agent = RobotAgent(settings)
    agent.initialize()
    return agent


def main(argv: Sequence[str] | None = None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["node"]:  # ROS owns the rest of the command line (--ros-args ...)
        return cmd_node(argv[1:])
    if argv[:1] == ["sim-driver"]:
        return cmd_sim_driver(argv[1:])
    parser = build_parser()
    args = parser.parse_args(argv)
    logging.basicConfig(level=[logging.WARNING, logging.INFO, logging.DEBUG][min(args.verbose, 2)],
                        format="%(levelname)s %(name)s: %(message)s", stream=sys.stderr)
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    try:
        settings = _settings(args)
        handler = {"run": cmd_run, "skills": cmd_skills, "chat": cmd_chat, "eval": cmd_eval,
                   "config": cmd_config, "doctor": cmd_doctor, "history": cmd_history,
                   "places": cmd_places, "recall": cmd_recall, "serve": cmd_serve}[args.command]
        return handler(args, settings)
    except ConfigError as exc:
        print(f"shadowhound: {_kind(exc)}: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except MemoryStoreError as exc:
        print(f"shadowhound: memory error: {exc}", file=sys.stderr)
        return EXIT_USAGE


def _kind(exc: ConfigError) -> str:
    return "backend unavailable" if type(exc).__name__ == "BackendUnavailable" else \
        "configuration error"


# -- run -----------------------------------------------------------------------------------


def _progress(stream: TextIO) -> ev.Listener:
    def show(event: ev.MissionEvent) -> None:
        if event.kind == ev.MISSION_STARTED:
            print(f"mission: {event.data['mission']!r}", file=stream)
        elif event.kind == ev.PLAN_READY:
            steps = event.data["plan"]["steps"]
            print(f"plan: {len(steps)} step(s)", file=stream)
        elif event.kind == ev.STEP_STARTED:
            step = event.data["step"]
            args = ", ".join(f"{k}={v}" for k, v in step["args"].items())
            print(f"  [{step['index']}] {step['skill']}({args}) ...", file=stream, flush=True)
        elif event.kind == ev.STEP_FINISHED:
            step = event.data["step"]
            mark = "ok" if step["status"] == "succeeded" else step["status"].upper()
            detail = step["output"] if step["status"] == "succeeded" else step["error"]
            print(f"  [{step['index']}] {mark}: {detail} ({step['robot_duration']:.1f} s robot "
                  "time)", file=stream, flush=True)
        stream.flush()

    return show


def _approver(agent: Any, ask: bool) -> ev.Listener:
    """Answer approval requests: with --yes at once, else by asking on the terminal."""

    def decide(request: dict[str, Any]) -> None:
        if not ask:
            agent.approve(request["request_id"])
            return
        print("approval needed: " + "; ".join(request["reasons"]), file=sys.stderr)
        print(f"approve within {request['timeout']:g} s? [y/N] ", end="", file=sys.stderr,
              flush=True)
        answer = sys.stdin.readline().strip().lower()
        if answer in ("y", "yes"):
            agent.approve(request["request_id"])
        else:
            agent.reject(request["request_id"], "declined at the terminal")

    def on_event(event: ev.MissionEvent) -> None:
        if event.kind == ev.APPROVAL_REQUIRED:
            # Ask on another thread: the mission thread waits with its time-out meanwhile.
            threading.Thread(target=decide, args=(event.data["request"],), daemon=True).start()

    return on_event


def cmd_run(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    agent = _agent(settings)
    if args.dry_run:
        return _dry_run(agent, args)
    if not args.quiet:
        agent.add_listener(_progress(sys.stderr))
    if args.yes or sys.stdin.isatty():
        agent.enable_approvals()
        agent.add_listener(_approver(agent, ask=not args.yes))
    box: dict[str, Any] = {}

    def work() -> None:
        try:
            box["result"] = agent.execute_mission(args.mission)
        except Exception as exc:  # a bug, not a mission failure: say so, never hide it
            logging.getLogger(__name__).exception("the mission crashed")
            box["crash"] = exc

    # The mission runs on a worker so that Ctrl-C here can stop the robot at once.
    worker = threading.Thread(target=work, name="shadowhound-mission", daemon=True)
    worker.start()
    interrupted = False
    try:
        while worker.is_alive():
            worker.join(0.1)
    except KeyboardInterrupt:
        interrupted = True
        agent.estop()
        worker.join(5.0)
    result = box.get("result")
    agent.cleanup()
    if "crash" in box:
        print(f"shadowhound: internal error: {box['crash']!r}; the robot was stopped",
              file=sys.stderr)
        return EXIT_FAILED
    if result is None:
        print("shadowhound: interrupted; the robot was stopped", file=sys.stderr)
        return EXIT_INTERRUPTED
    if args.json:
        out = result.to_dict()
        json.dump(out, sys.stdout, separators=(",", ":"))
        sys.stdout.write("\n")
    else:
        st = result.robot
        print(result.response)
        print(f"robot: x={st.x:.3f} m y={st.y:.3f} m yaw={st.yaw:.4f} rad "
              f"({st.to_dict()['yaw_deg']} deg) posture={st.posture.value} "
              f"battery={st.battery:.1f}%")
    if interrupted:
        return EXIT_INTERRUPTED
    return EXIT_OK if result.success else EXIT_FAILED


def _dry_run(agent: Any, args: argparse.Namespace) -> int:
    result = agent.dry_run(args.mission)
    agent.cleanup()
    if args.json:
        json.dump(result.to_dict(), sys.stdout, separators=(",", ":"))
        sys.stdout.write("\n")
    else:
        for step in result.steps:
            params = ", ".join(f"{k}={v}" for k, v in step.args.items())
            print(f"  [{step.index}] {step.skill}({params})")
        path = " -> ".join(f"({p.x:.2f}, {p.y:.2f})" for p in result.predicted_path)
        if path:
            print(f"predicted path: {path}")
        print(result.response)
    return EXIT_OK if result.success else EXIT_FAILED


# -- skills ----------------------------------------------------------------------------------


def cmd_skills(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    from .skills import default_registry

    described = default_registry().describe()
    if args.json:
        json.dump(described, sys.stdout, indent=2)
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
    for key, sign in (("minimum", ">="), ("exclusiveMinimum", ">"), ("maximum", "<="),
                      ("exclusiveMaximum", "<")):
        bound = next((o[key] for o in options if key in o), None)
        if bound is not None:
            text += f" {sign}{bound:g}"
    if prop.get("description"):
        text += f" - {prop['description']}"
    return text


# -- chat --------------------------------------------------------------------------------------

_CHAT_HELP = ("Ask a question (where are you? battery? what do you see? what did you do?), or: "
              "/run MISSION, /status, /skills, /estop, /release, /help, /quit")


def cmd_chat(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    agent = _agent(settings)
    interactive = sys.stdin.isatty()
    if interactive:
        print("ShadowHound chat. " + _CHAT_HELP)
    try:
        while True:
            if interactive:
                print("you> ", end="", flush=True)
            line = sys.stdin.readline()
            if not line:
                break
            line = line.strip()
            if not line:
                continue
            if line in ("/quit", "/exit"):
                break
            print(_chat_line(agent, line), flush=True)
    except KeyboardInterrupt:
        agent.estop()
    finally:
        agent.cleanup()
    return EXIT_OK


def _chat_line(agent: Any, line: str) -> str:
    if line.startswith("/run"):
        mission = line[4:].strip()
        if not mission:
            return "usage: /run MISSION"
        result = agent.execute_mission(mission)
        return ("ok: " if result.success else "failed: ") + result.response
    commands = {
        "/status": lambda: json.dumps(agent.get_robot_status()),
        "/skills": lambda: ", ".join(s["name"] for s in agent.get_available_skills()),
        "/estop": lambda: (agent.estop(), "e-stop latched; /release to release it")[1],
        "/release": lambda: (agent.release_estop(), "e-stop released")[1],
        "/help": lambda: _CHAT_HELP,
    }
    if line.startswith("/"):
        action = commands.get(line.split()[0])
        return action() if action else f"unknown command {line.split()[0]!r}. {_CHAT_HELP}"
    return str(agent.chat(line))


# -- eval ----------------------------------------------------------------------------------------


def cmd_eval(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    from .evaluation import CaseFileError, load_cases, run_cases

    try:
        cases = load_cases(args.file)
    except CaseFileError as exc:
        print(f"shadowhound: {exc}", file=sys.stderr)
        return EXIT_USAGE

    def show(outcome: Any) -> None:
        if args.json:
            return
        mark = "PASS" if outcome.passed else "FAIL"
        print(f"{mark}  {outcome.case.mission!r}")
        for failure in outcome.failures:
            print(f"      {failure}  [{outcome.response}]")

    outcomes = run_cases(cases, settings, on_case=show)
    passed = sum(o.passed for o in outcomes)
    total = len(outcomes)
    rate = passed / total if total else 0.0
    if args.json:
        json.dump({"total": total, "passed": passed, "failed": total - passed,
                   "pass_rate": round(rate, 4), "cases": [o.to_dict() for o in outcomes]},
                  sys.stdout, indent=2)
        sys.stdout.write("\n")
    else:
        print(f"{passed}/{total} cases passed ({100 * rate:.1f}%)")
    return EXIT_OK if passed == total and total else EXIT_FAILED


# -- config --------------------------------------------------------------------------------------


def cmd_config(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    import yaml

    sys.stdout.write(yaml.safe_dump(json.loads(settings.model_dump_json()), sort_keys=False))
    return EXIT_OK


# -- memory --------------------------------------------------------------------------------------


def _memory(settings: ShadowHoundConfig) -> Any:
    from .memory.service import AgentMemory

    return AgentMemory.open(settings)


def cmd_history(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    if not settings.memory.enabled:
        print("shadowhound: mission history is off (memory.enabled: false)", file=sys.stderr)
        return EXIT_USAGE
    memory = _memory(settings)
    assert memory.history is not None
    try:
        if args.mission_id:
            record = memory.history.get(args.mission_id)
            if record is None:
                print(f"shadowhound: no mission {args.mission_id!r} in "
                      f"{memory.history.path}", file=sys.stderr)
                return EXIT_FAILED
            json.dump(record, sys.stdout, indent=2, default=str)
            sys.stdout.write("\n")
            return EXIT_OK
        rows = memory.history.recent(max(1, args.limit))
        if args.json:
            json.dump(rows, sys.stdout, indent=2)
            sys.stdout.write("\n")
        for row in [] if args.json else rows:
            when = time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(row["started_at"]))
            print(f"{row['id']}  {when}  {row['status']:<11} {row['mission'][:60]!r}")
        return EXIT_OK
    finally:
        memory.close()


def cmd_places(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    memory = _memory(settings)
    try:
        if args.forget:
            if not memory.places.forget(args.forget):
                print(f"shadowhound: no taught place {args.forget!r}", file=sys.stderr)
                return EXIT_FAILED
            print(f"forgot {args.forget!r}")
            return EXIT_OK
        taught = memory.places.all()
        listing = {**{n: {"x": x, "y": y, "source": "profile"}
                      for n, (x, y) in settings.places.items()},
                   **{n: {"x": x, "y": y, "yaw": yaw, "source": "taught"}
                      for n, (x, y, yaw) in taught.items()}}
        if args.json:
            json.dump(listing, sys.stdout, indent=2)
            sys.stdout.write("\n")
        else:
            for name, place in listing.items():
                print(f"{name:<20} x={place['x']:7.2f} y={place['y']:7.2f}  {place['source']}")
        return EXIT_OK
    finally:
        memory.close()


def cmd_recall(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    memory = _memory(settings)
    try:
        found = memory.search(args.query)
        print("\n".join(found) if found else "nothing remembered about that")
        return EXIT_OK
    finally:
        memory.close()


# -- serve ---------------------------------------------------------------------------------------


def cmd_serve(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    try:
        from .web import serve_main
    except ImportError as exc:
        print(f"shadowhound: the web dashboard needs the 'web' extra "
              f"(pip install 'shadowhound[web]'): {exc}", file=sys.stderr)
        return EXIT_USAGE
    return int(serve_main(settings, args.host, args.port, args.token))


# -- node ----------------------------------------------------------------------------------------


def cmd_node(ros_argv: list[str]) -> int:
    try:
        from .ros.node import main as node_main
    except ImportError as exc:
        print(f"shadowhound: the ROS 2 node needs rclpy and the shadowhound_interfaces package "
              f"(pip install 'shadowhound[ros]' and bash scripts/build_ros.sh): {exc}",
              file=sys.stderr)
        return EXIT_USAGE
    return node_main(ros_argv)


def cmd_sim_driver(ros_argv: list[str]) -> int:
    try:
        from .ros.sim_driver import main as driver_main
    except ImportError as exc:
        print(f"shadowhound: the simulated Go2 driver needs rclpy and the go2_interfaces package "
              f"(pip install 'shadowhound[ros]' and bash scripts/build_ros.sh): {exc}",
              file=sys.stderr)
        return EXIT_USAGE
    return driver_main(ros_argv)


# -- doctor --------------------------------------------------------------------------------------


def cmd_doctor(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    print(f"ok  configuration: profile {settings.profile!r}, backend {settings.backend!r}, "
          f"robot {settings.robot!r}")
    s = settings.safety
    print(f"ok  safety limits: {s.max_linear_speed:g} m/s, {s.max_angular_speed:g} rad/s, "
          f"{s.max_step_distance:g} m per step, geofence {s.geofence_radius:g} m, risky tricks "
          f"{'allowed' if s.allow_risky_tricks else 'refused'}")
    if settings.backend == "offline":
        print("ok  planner: offline rules (no network, no model)")
        return EXIT_OK
    from .llm import LLMBackend

    for line in LLMBackend(settings.backend, settings.llm).check():
        print(f"ok  {line}")
    print(f"ok  planning mode {settings.llm.mode!r}, plan format {settings.llm.plan_format!r}, "
          f"vision {'on' if settings.llm.vision else 'off'}")
    return EXIT_OK


if __name__ == "__main__":
    sys.exit(main())
