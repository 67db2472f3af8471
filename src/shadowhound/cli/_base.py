"""What every command shares: how a command reports an error (also as the one JSON object
`run --json` promises), and building an agent from settings. Exit codes: shadowhound.exit_codes."""

from __future__ import annotations

import sys
from typing import Any

from .. import jsonout
from ..config import ShadowHoundConfig

# Error kinds (`error_kind` of a JSON answer) and how they are named on stderr.
ERROR_LABELS = {
    "usage": "usage error",
    "configuration": "configuration error",
    "backend_unavailable": "backend unavailable",
    "memory": "memory error",
    "interrupted": "interrupted",
    "internal": "internal error",
}


def report_error(
    kind: str, message: str, code: int, *, json_out: bool = False, mission: str | None = None
) -> int:
    """Say on stderr what went wrong; with `json_out` also print the one JSON object on stdout.
    Returns `code`, the exit code.

    The object has a mission result's first keys (`success` false, `status` "error",
    `mission`, `response`, `error` the message) plus `error_kind` and `exit_code`.
    """
    label = ERROR_LABELS[kind]
    print(f"shadowhound: {label}: {message}", file=sys.stderr, flush=True)
    if json_out:
        print_json(
            {
                "success": False,
                "status": "error",
                "mission": mission,
                "response": f"{label}: {message}",
                "error": message,
                "error_kind": kind,
                "exit_code": code,
            }
        )
    return code


def print_json(answer: dict[str, Any]) -> None:
    """One JSON object on one line of stdout (strict JSON: see jsonout)."""
    jsonout.dump(answer, sys.stdout, separators=(",", ":"))
    sys.stdout.write("\n")
    sys.stdout.flush()


def make_agent(settings: ShadowHoundConfig) -> Any:
    """An initialized agent (raises ConfigError, e.g. an unreachable backend)."""
    from ..agent import RobotAgent

    agent = RobotAgent(settings)
    agent.initialize()
    return agent
