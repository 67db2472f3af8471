"""`shadowhound`: the command line. Commands live in `missions` (run, eval), `chat`, `memory`
(history, places, recall), `tools` and `ros_tools` (node, sim-driver, send, estop, sim-fault,
loopback-env).

Exit codes (shadowhound.exit_codes): 0 success, 1 mission (or evaluation) failure, 2 usage or
configuration error, 130 interrupted (the robot is stopped first), 141 the output went away (a
closed pipe: the command ends quietly).
"""

from __future__ import annotations

import argparse
import logging
import os
import shlex
import sys
from collections.abc import Sequence
from typing import Any

from ..config import ShadowHoundConfig, available_profiles, load_config
from ..errors import BackendUnavailable, ConfigError, MemoryStoreError, UsageError
from ..exit_codes import EXIT_BROKEN_PIPE, EXIT_FAILED, EXIT_INTERRUPTED, EXIT_OK, EXIT_USAGE
from ._base import report_error
from .chat import cmd_chat
from .memory import cmd_history, cmd_places, cmd_recall
from .missions import cmd_eval, cmd_run
from .parser import BACKENDS, build_parser
from .ros_tools import (
    cmd_estop,
    cmd_loopback_env,
    cmd_node,
    cmd_send,
    cmd_sim_driver,
    cmd_sim_fault,
)
from .tools import (
    cmd_config,
    cmd_doctor,
    cmd_mcp,
    cmd_serve,
    cmd_skills,
)

__all__ = ["EXIT_FAILED", "EXIT_INTERRUPTED", "EXIT_OK", "EXIT_USAGE", "build_parser", "main"]


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
    if getattr(args, "robot", None) and load_config(profile).robot.type != args.robot:
        overrides["robot"] = args.robot  # another backend: the profile's settings go
    llm = {
        k: v
        for k, v in (("model", args.model), ("base_url", args.base_url), ("mode", args.mode))
        if v is not None
    } | options
    if llm:
        overrides["llm"] = llm
    return load_config(profile, overrides)


def main(argv: Sequence[str] | None = None) -> int:
    """The `shadowhound` command. Returns its exit code (shadowhound.exit_codes)."""
    try:
        try:
            code = _main(argv)
        finally:  # --help and --version end in SystemExit: their output is flushed too
            sys.stdout.flush()  # so a pipe closed now is noticed here, not at exit
    except BrokenPipeError:
        return _output_gone()
    return code


def _output_gone() -> int:
    """Whoever read stdout went away (`| head -1`): end quietly, as cat and git do.

    What is still buffered goes to /dev/null, so the interpreter's own flush at exit does not
    complain either (the recipe of Python's signal module documentation).
    """
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, sys.stdout.fileno())
    os.close(devnull)
    return EXIT_BROKEN_PIPE


def _main(argv: Sequence[str] | None) -> int:
    argv = list(sys.argv[1:] if argv is None else argv)
    if argv[:1] == ["node"]:  # ROS owns the rest of the command line (--ros-args ...)
        return cmd_node(argv[1:])
    if argv[:1] == ["sim-driver"]:
        return cmd_sim_driver(argv[1:])
    parser = build_parser()
    # A line that cannot be parsed has no `args` to ask; `run ... --json` in it is enough.
    json_out = "run" in argv and "--json" in argv
    try:
        args, extra = parser.parse_known_args(argv)
        if extra:
            raise _unrecognized(parser, argv, args, extra)
    except UsageError as exc:
        sys.stderr.write(exc.usage)
        return report_error("usage", str(exc), EXIT_USAGE, json_out=json_out)
    json_out = args.command == "run" and args.json
    mission = args.mission if args.command == "run" else None
    logging.basicConfig(
        level=[logging.WARNING, logging.INFO, logging.DEBUG][min(args.verbose, 2)],
        format="%(levelname)s %(name)s: %(message)s",
        stream=sys.stderr,
    )
    if args.command is None:
        parser.print_help(sys.stderr)
        return EXIT_USAGE
    try:
        settings = _settings(args)
        handler = {
            "run": cmd_run,
            "skills": cmd_skills,
            "chat": cmd_chat,
            "eval": cmd_eval,
            "config": cmd_config,
            "doctor": cmd_doctor,
            "history": cmd_history,
            "places": cmd_places,
            "recall": cmd_recall,
            "serve": cmd_serve,
            "mcp": cmd_mcp,
            "send": cmd_send,
            "estop": cmd_estop,
            "sim-fault": cmd_sim_fault,
            "loopback-env": cmd_loopback_env,
        }[args.command]
        return handler(args, settings)
    except ConfigError as exc:
        return report_error(_kind(exc), str(exc), EXIT_USAGE, json_out=json_out, mission=mission)
    except MemoryStoreError as exc:
        return report_error("memory", str(exc), EXIT_USAGE, json_out=json_out, mission=mission)
    except BrokenPipeError:  # the reader went away: main() ends quietly
        raise
    except KeyboardInterrupt:  # before the mission ran (while connecting, say): nothing moved
        what = "stopped before the mission started" if args.command == "run" else "stopped"
        return report_error(
            "interrupted", what, EXIT_INTERRUPTED, json_out=json_out, mission=mission
        )
    except Exception as exc:  # a bug: the traceback goes to the log, the answer is still one
        logging.getLogger(__name__).exception("shadowhound %s crashed", args.command)
        return report_error("internal", repr(exc), EXIT_FAILED, json_out=json_out, mission=mission)


def _unrecognized(
    parser: argparse.ArgumentParser, argv: list[str], args: argparse.Namespace, extra: list[str]
) -> UsageError:
    """What argparse says of arguments it does not know, except for a mission typed without
    quotes (`run walk forward 1 meter`): that gets the command with the mission quoted."""
    words = [args.mission, *extra] if args.command in ("run", "send") else []
    if not words or any(w.startswith("-") for w in extra):
        return UsageError(
            f"{parser.prog}: unrecognized arguments: {' '.join(extra)}", parser.format_usage()
        )
    return UsageError(
        f"the mission of {args.command} is one argument, but it came as {len(words)} words; "
        f"put it in quotes: {shlex.join(['shadowhound', *_quoted(argv, words, args.command)])}",
        "",
    )


def _quoted(argv: list[str], words: list[str], command: str) -> list[str]:
    """`argv` with the mission's `words` (in order, after `command`) made one argument where
    the first of them stood; the options stay where they were."""
    spots: list[int] = []
    for i in range(argv.index(command) + 1 if command in argv else 0, len(argv)):
        if len(spots) < len(words) and argv[i] == words[len(spots)]:
            spots.append(i)
    if len(spots) < len(words):  # not found as typed: the plain command
        return [command, " ".join(words)]
    quoted = [a for i, a in enumerate(argv) if i not in spots[1:]]
    quoted[spots[0]] = " ".join(words)
    return quoted


def _kind(exc: ConfigError) -> str:
    return "backend_unavailable" if isinstance(exc, BackendUnavailable) else "configuration"
