"""The MCP server (the `mcp` extra: the official MCP Python SDK).

    shadowhound mcp                      # stdio, for Claude Desktop and other MCP clients
    shadowhound mcp --http --port 8765   # Streamable HTTP at http://127.0.0.1:8765/mcp

    from shadowhound.mcp import McpRobotServer   # the SDK Server for an agent: .server

Importing `shadowhound` never imports this package, and importing this package does not import
the SDK until `McpRobotServer` or `main` is used, so a missing extra gets a clear message.
"""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING, Any

from ..exit_codes import EXIT_OK, EXIT_USAGE

if TYPE_CHECKING:
    from ..config import ShadowHoundConfig
    from .desk import McpDesk
    from .server import McpRobotServer

__all__ = ["McpDesk", "McpRobotServer", "main"]

_LAZY = {"McpRobotServer": "server", "McpDesk": "desk"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        from importlib import import_module

        return getattr(import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def main(
    settings: ShadowHoundConfig,
    *,
    http: bool = False,
    host: str = "127.0.0.1",
    port: int = 8765,
    token: str | None = None,
    allow_release_estop: bool = False,
    session_idle: float | None = None,
    max_sessions: int | None = None,
) -> int:
    """`shadowhound mcp`: serve until the client leaves (stdio) or Ctrl-C (HTTP).

    `token` defaults to $SHADOWHOUND_TOKEN (HTTP only). `allow_release_estop` offers the
    `release_estop` tool, which asks the person each time (MCP elicitation). `session_idle`
    (seconds) and `max_sessions` bound HTTP sessions (default: `SessionLimits`). Returns 2 with
    a message on stderr when the extra is missing, the robot cannot be reached or an option or
    the binding is not allowed. Nothing is printed on stdout: over stdio it belongs to the
    protocol.
    """
    try:
        import anyio

        from .server import McpRobotServer
        from .transport import ServeError, run_stdio, serve_http
    except ModuleNotFoundError as exc:
        print(
            f"shadowhound mcp: the MCP server needs the 'mcp' extra ({exc.name} is not "
            "installed): pip install 'shadowhound[mcp]'",
            file=sys.stderr,
        )
        return EXIT_USAGE
    from ..agent import RobotAgent, RobotAgentConfig
    from ..errors import ConfigError
    from .limits import DEFAULT_IDLE_TIMEOUT, DEFAULT_MAX_SESSIONS, SessionLimits

    token = (token or os.environ.get("SHADOWHOUND_TOKEN") or None) if http else None
    try:
        limits = SessionLimits(
            DEFAULT_IDLE_TIMEOUT if session_idle is None else session_idle,
            DEFAULT_MAX_SESSIONS if max_sessions is None else max_sessions,
        )
        if http:
            from ..serving import check_binding

            check_binding(host, token, what="the MCP server")  # before the robot is touched
        agent = RobotAgent(RobotAgentConfig(robot=_robot(settings), settings=settings))
        agent.initialize()
    except (ConfigError, ServeError) as exc:
        print(f"shadowhound mcp: {exc}", file=sys.stderr)
        return EXIT_USAGE
    robot_server = McpRobotServer(agent, allow_release_estop=allow_release_estop)
    from ..serving import settle_heap

    settle_heap()  # a long-running server: keep full collections short (serving.py)

    def ready(url: str) -> None:
        print(
            f"ShadowHound MCP server on {url} (robot {agent.robot.name}"
            + (", token required" if token else "")
            + "); Ctrl-C stops",
            file=sys.stderr,
            flush=True,
        )

    try:
        if http:
            anyio.run(serve_http, robot_server, host, port, token, ready, limits)
        else:
            anyio.run(run_stdio, robot_server)
    except ServeError as exc:
        print(f"shadowhound mcp: {exc}", file=sys.stderr)
        return EXIT_USAGE
    except KeyboardInterrupt:
        print("shadowhound mcp: stopped; the robot is stopped", file=sys.stderr)
    finally:
        agent.cleanup()
    return EXIT_OK


def _robot(settings: ShadowHoundConfig) -> Any:
    """The profile's robot (robot/factory.py): the simulator, or a Go2 with the profile's
    namespace and topics."""
    from ..robot.factory import make_robot

    return make_robot(settings)
