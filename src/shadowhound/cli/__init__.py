"""`shadowhound`: the command line. Commands live in `missions` (run, chat, eval) and `tools`.

Exit codes: 0 success, 1 mission (or evaluation) failure, 2 usage or configuration error,
130 interrupted (the robot is stopped first).
"""

from __future__ import annotations

import argparse
import logging
import sys
from collections.abc import Sequence
from typing import Any

from .. import __version__
from ..config import ConfigError, ShadowHoundConfig, available_profiles, load_config
from ..memory.history import MemoryStoreError
from ._base import EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE
from .missions import cmd_chat, cmd_eval, cmd_run
from .tools import (
    cmd_config,
    cmd_doctor,
    cmd_history,
    cmd_node,
    cmd_places,
    cmd_recall,
    cmd_serve,
    cmd_sim_driver,
    cmd_skills,
)

__all__ = ["EXIT_FAILED", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_USAGE", "build_parser", "main"]


BACKENDS = ["offline", "openai", "ollama", "vllm", "llamacpp"]


def _common(parser: argparse.ArgumentParser, suppress: bool, compare: bool = False) -> None:
    default: Any = argparse.SUPPRESS if suppress else None
    parser.add_argument("--config", "-c", metavar="PROFILE|PATH", default=default,
                        help="profile name (" + ", ".join(available_profiles()) +
                        ") or a YAML file; default $SHADOWHOUND_CONFIG or offline")
    if compare:  # eval: several planners side by side
        parser.add_argument("--backend", default=default, action="append",
                            metavar="BACKEND[:OPTION...]",
                            help="a planner to evaluate; repeat to compare several. BACKEND is "
                                 f"one of {', '.join(BACKENDS)}; OPTIONs: hybrid, llm (hybrid "
                                 "off), json_schema, plain, tools, react; e.g. --backend offline "
                                 "--backend llamacpp --backend llamacpp:llm:plain")
    else:
        parser.add_argument("--backend", default=default, choices=BACKENDS,
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
    _common(evaluate, suppress=True, compare=True)
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


def _settings(args: argparse.Namespace, planner: str | None = None) -> ShadowHoundConfig:
    """The settings of the command line, for `planner` ("BACKEND[:OPTION...]", see eval)."""
    from ..evaluation import planner_options

    overrides: dict[str, Any] = {}
    profile = args.config
    if planner is None and isinstance(args.backend, str):
        planner = args.backend
    backend, options = planner_options(planner) if planner else ("", {})
    if backend:
        if backend not in BACKENDS:
            raise ConfigError(f"unknown backend {backend!r}; allowed: {', '.join(BACKENDS)}")
        overrides["backend"] = backend
        if profile is None and backend in available_profiles():
            profile = backend  # --backend ollama alone means the ollama profile
    if args.time_scale is not None:
        overrides["sim"] = {"time_scale": args.time_scale}
    llm = {k: v for k, v in (("model", args.model), ("base_url", args.base_url),
                             ("mode", args.mode)) if v is not None} | options
    if llm:
        overrides["llm"] = llm
    return load_config(profile, overrides)



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


