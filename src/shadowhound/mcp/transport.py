"""Serving the MCP server: over stdio (desktop clients start it as a child) or Streamable HTTP.

HTTP follows `shadowhound serve`'s rules: it binds loopback unless a token is set; with a
token every request needs `Authorization: Bearer <token>`; without one only loopback Host
names are answered (DNS rebinding), and a request with an `Origin` must come from the
server's own origin (the MCP spec's rule for HTTP servers: a web page may not drive it).
Either way the robot is stopped when the server ends. Behind the gate, `Sessions` cancels the
calls whose clients drop their connections and keeps sessions few and short-lived.
"""

from __future__ import annotations

import hmac
import logging
import sys
from collections.abc import Callable
from urllib.parse import urlsplit

import anyio
import uvicorn
from mcp.server.stdio import stdio_server
from mcp.server.transport_security import TransportSecuritySettings

from ..errors import ServeError
from ..serving import LOOPBACK_HOSTS, bind, check_binding, hostname, send_json
from .limits import SessionLimits
from .server import McpRobotServer
from .sessions import ASGIApp, Receive, Scope, Send, Sessions

if sys.version_info < (3, 11):
    from exceptiongroup import BaseExceptionGroup  # anyio's dependency before Python 3.11

log = logging.getLogger(__name__)

MCP_PATH = "/mcp"
MAX_BODY = 1024 * 1024  # bytes: a tool call is small; a huge one is refused before parsing

__all__ = [
    "MCP_PATH",
    "McpGate",
    "ServeError",
    "SessionLimits",
    "bind",
    "http_app",
    "run_stdio",
    "serve_http",
]


async def run_stdio(robot_server: McpRobotServer) -> None:
    """Serve one client over stdin/stdout until it closes them; then stop the robot.

    The end of stdin ends the SDK's dispatcher, which cancels every call in flight: a call
    following a mission stops it (`McpRobotServer`), and `close` stops the robot again. A
    client that closes its end of stdout first is gone too: the write that finds the pipe
    broken ends the server the same way (not as an error).
    """
    server = robot_server.server
    try:
        async with stdio_server() as (read, write):
            await server.run(read, write, server.create_initialization_options())
    except BaseException as exc:
        if not _only_broken_pipes(exc):
            raise
        log.info("the stdio client closed its end of the pipe")
    finally:
        robot_server.close()


def _only_broken_pipes(exc: BaseException) -> bool:
    if isinstance(exc, BaseExceptionGroup):
        return all(_only_broken_pipes(e) for e in exc.exceptions)
    return isinstance(exc, BrokenPipeError)


class McpGate:
    """Token, Host and Origin checks in front of the MCP endpoint (one ASGI layer)."""

    def __init__(self, app: ASGIApp, token: str | None, allowed_hosts: set[str]) -> None:
        self.app = app
        self.token = token
        self.allowed_hosts = allowed_hosts

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = {
            k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])
        }
        problem = self._check(headers)
        if problem is None:
            await self.app(scope, receive, send)
            return
        status, detail = problem
        extra = [(b"www-authenticate", b"Bearer")] if status == 401 else []
        error = {"jsonrpc": "2.0", "id": None, "error": {"code": -32600, "message": detail}}
        await send_json(send, status, error, extra)

    def _check(self, headers: dict[str, str]) -> tuple[int, str] | None:
        raw_host = headers.get("host", "")
        host = hostname(raw_host)
        if self.token is None and (host is None or host not in self.allowed_hosts):
            return 421, (
                f"host {raw_host[:100]!r} is not allowed: without a token the MCP "
                "server answers only on loopback names"
            )
        origin = headers.get("origin")
        if origin is not None and not _same_origin(origin, raw_host):
            return 403, (
                f"origin {origin[:100]!r} is not allowed: the MCP server takes no "
                "requests from web pages of other origins"
            )
        if self.token is None:
            return None
        auth = headers.get("authorization", "")
        offered = auth[7:].strip() if auth[:7].lower() == "bearer " else ""
        if offered and hmac.compare_digest(offered.encode(), self.token.encode()):
            return None
        return 401, "a valid token is required: send 'Authorization: Bearer <token>'"


def _same_origin(origin: str, host: str) -> bool:
    """Whether a request's Origin is the server's own (the scheme http or https)."""
    parts = urlsplit(origin.strip())
    return (
        parts.scheme.lower() in ("http", "https")
        and parts.netloc.lower() == host.lower()
        and not parts.path
        and not parts.query
    )


def http_app(
    robot_server: McpRobotServer,
    host: str,
    token: str | None,
    limits: SessionLimits | None = None,
) -> ASGIApp:
    """The Streamable HTTP app at /mcp behind `Sessions` and `McpGate` (which does the
    Host/Origin checks itself, so the SDK's own loopback-only list does not refuse a
    token-holding client). `Sessions` alone ends sessions, so the SDK's own idle time-out and
    session limit are off: two clocks would disagree on which sessions are open."""
    app = robot_server.server.streamable_http_app(
        streamable_http_path=MCP_PATH,
        max_request_body_size=MAX_BODY,
        host=host,
        transport_security=TransportSecuritySettings(enable_dns_rebinding_protection=False),
        session_idle_timeout=None,
        max_sessions=None,
    )
    sessions = Sessions(app, limits or SessionLimits(), MCP_PATH, MAX_BODY)
    allowed = set(LOOPBACK_HOSTS) | ({host.lower()} if host not in ("0.0.0.0", "::") else set())
    return McpGate(sessions, token, allowed)


async def serve_http(
    robot_server: McpRobotServer,
    host: str,
    port: int,
    token: str | None,
    on_ready: Callable[[str], None] | None = None,
    limits: SessionLimits | None = None,
) -> None:
    """Serve Streamable HTTP until cancelled (Ctrl-C, SIGTERM); then stop the robot.

    Raises ServeError before listening when the binding is not allowed.
    """
    check_binding(host, token, what="the MCP server")
    sock = bind(host, port)
    app = http_app(robot_server, host, token, limits)
    # No access log: nothing secret is in MCP URLs, but the log would be noise on stderr.
    server = uvicorn.Server(
        uvicorn.Config(
            app, log_level="warning", access_log=False, lifespan="on", timeout_graceful_shutdown=2
        )
    )
    shown = f"[{host}]" if ":" in host else host
    try:
        async with anyio.create_task_group() as group:
            group.start_soon(server.serve, [sock])
            while not server.started:
                await anyio.sleep(0.01)
            if on_ready is not None:
                on_ready(f"http://{shown}:{sock.getsockname()[1]}{MCP_PATH}")
    finally:
        sock.close()
        robot_server.close()
