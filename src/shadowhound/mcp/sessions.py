"""The Streamable HTTP sessions of the MCP server: a call whose client drops its connection is
cancelled, and a session ends soon after its client has gone.

Why a layer of our own: a handshake-era client (protocol 2024-11-05 to 2025-11-25) opens a
session, and the SDK runs each of its calls in the session's task, not in the HTTP request's.
When the client closes a call's response stream, the SDK ends the stream and lets the call run
on (that era's rule: a disconnect is not a cancel, the client may resume the stream; this server
keeps no events to resume from), so a mission walked on for a client that was gone. This layer
does what a leaving client should have done: for every request whose answer never went out in
full, it sends the session `notifications/cancelled`, and the SDK cancels the call. (Protocol
2026-07-28 has no sessions: the SDK cancels a call itself when its request's connection drops.
Over stdio the end of stdin cancels every call.)

A session ends (`SessionLimits`):
- at once when its client drops a connection in the middle of an answer (a call's event stream
  or the session's GET stream) and has no other request open on it: the client is gone;
- after `idle_timeout` seconds with no request in flight (an open GET stream is one);
- when a new session would pass `max_sessions`: the least recently used idle session makes room;
  while every session has a request in flight, the new one is refused (503, saying the limit).
Its id then answers 404, on which the specification tells a client to initialize again. Every
call of an ended session is cancelled (the robot stops). Sessions are ended and calls cancelled
through the SDK's own door: an HTTP DELETE, or a notification POSTed with the session's id.
"""

from __future__ import annotations

import json
import logging
from collections.abc import Awaitable, Callable, MutableMapping
from dataclasses import dataclass
from typing import Any

import anyio
from mcp_types.version import HANDSHAKE_PROTOCOL_VERSIONS

from ..serving import send_json
from .limits import SessionLimits

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]

__all__ = ["ASGIApp", "Receive", "Scope", "Send", "Sessions"]

log = logging.getLogger(__name__)

SESSION_HEADER = "mcp-session-id"
VERSION_HEADER = "mcp-protocol-version"
_OWN_REQUEST_TIMEOUT = 5.0  # seconds for a cancel or close of ours to reach the SDK
# What a request of this layer's own takes from a client's (the SDK's app adds its own keys).
_TEMPLATE_KEYS = (
    "type",
    "asgi",
    "http_version",
    "scheme",
    "server",
    "client",
    "root_path",
    "state",
    "headers",
)


@dataclass(eq=False)
class _Session:
    id: str
    last_active: float  # anyio.current_time() when a request last began or ended
    requests: int = 0  # requests of this session being served now (an open GET stream is one)


class _Exchange:
    """One HTTP request on its way through: its body (read up front) and whether the whole
    answer went out."""

    def __init__(self, receive: Receive, send: Send, on_start: Callable[[Message], None]) -> None:
        self._receive = receive
        self._send = send
        self._on_start = on_start
        self.body = b""
        self._more_body = True
        self._replayed = True  # until read_body has read something to replay
        self.status: int | None = None
        self.answered = False

    async def read_body(self, limit: int) -> None:
        """Read the body up to `limit` bytes (the SDK refuses a longer one itself)."""
        self._replayed = False
        while self._more_body and len(self.body) <= limit:
            message = await self._receive()
            if message["type"] != "http.request":
                self._more_body = False  # disconnected before the body was complete
                return
            self.body += message.get("body", b"")
            self._more_body = bool(message.get("more_body", False))

    async def receive(self) -> Message:
        if not self._replayed:
            self._replayed = True
            return {"type": "http.request", "body": self.body, "more_body": self._more_body}
        return await self._receive()

    async def send(self, message: Message) -> None:
        if message["type"] == "http.response.start":
            self.status = int(message["status"])
            self._on_start(message)
        await self._send(message)
        if message["type"] == "http.response.body" and not message.get("more_body", False):
            self.answered = True

    def request_ids(self) -> list[Any]:
        """The JSON-RPC request ids in the body (a batch may hold several)."""
        try:
            parsed = json.loads(self.body)
        except ValueError:
            return []
        items = parsed if isinstance(parsed, list) else [parsed]
        return [
            m["id"]
            for m in items
            if isinstance(m, dict) and "method" in m and m.get("id") is not None
        ]

    def is_initialize(self) -> bool:
        try:
            parsed = json.loads(self.body)
        except ValueError:
            return False
        return isinstance(parsed, dict) and parsed.get("method") == "initialize"


class Sessions:
    """ASGI layer in front of the SDK's Streamable HTTP app: keeps its sessions' lives short
    and cancels the calls their clients drop (see the module's docstring).

    `path` is the MCP endpoint the layer's own requests go to; `max_body` the SDK's body
    limit, up to which request bodies are read here first.
    """

    def __init__(self, app: ASGIApp, limits: SessionLimits, path: str, max_body: int) -> None:
        self.app = app
        self.limits = limits
        self.path = path
        self.max_body = max_body
        self._open: dict[str, _Session] = {}
        self._opening = 0  # initialize requests let in and not yet answered
        self._template: Scope | None = None  # a client's request, the mould for our own

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] == "lifespan":  # the server's life: expire idle sessions meanwhile
            async with anyio.create_task_group() as group:
                group.start_soon(self._expire_idle)
                await self.app(scope, receive, send)
                group.cancel_scope.cancel()
            return
        if scope["type"] != "http":
            await self.app(scope, receive, send)
            return
        headers = _headers(scope)
        version = headers.get(VERSION_HEADER)
        session_id = headers.get(SESSION_HEADER)
        if version is not None and version not in HANDSHAKE_PROTOCOL_VERSIONS:
            await self.app(scope, receive, send)  # no sessions: the SDK cancels on a drop
            return
        self._template = {k: scope[k] for k in _TEMPLATE_KEYS if k in scope}
        if session_id is None and scope["method"] == "POST":
            await self._open_session(scope, receive, send)
        elif session_id is not None and session_id in self._open:
            await self._serve(self._open[session_id], scope, receive, send)
        else:
            await self.app(scope, receive, send)  # the SDK answers (404 for an unknown id)

    # -- requests ------------------------------------------------------------------------------

    async def _open_session(self, scope: Scope, receive: Receive, send: Send) -> None:
        opened: list[_Session] = []

        def on_start(message: Message) -> None:
            new_id = _header(message, SESSION_HEADER)
            if int(message["status"]) < 400 and new_id and new_id not in self._open:
                session = _Session(new_id, anyio.current_time(), requests=1)
                self._open[new_id] = session  # it holds its place now, not the reservation
                self._opening -= 1
                opened.append(session)

        exchange = _Exchange(receive, send, on_start)
        await exchange.read_body(self.max_body)
        if not exchange.is_initialize():  # the SDK refuses it: it opens nothing
            await self.app(scope, exchange.receive, send)
            return
        if not await self._reserve():
            await _refuse(send, self.limits.max_sessions, exchange)
            return
        try:
            await self.app(scope, exchange.receive, exchange.send)
        finally:
            if opened:
                await self._finish(opened[0], exchange, scope)
            else:
                self._opening -= 1

    async def _serve(self, session: _Session, scope: Scope, receive: Receive, send: Send) -> None:
        session.requests += 1
        session.last_active = anyio.current_time()
        exchange = _Exchange(receive, send, _ignore)
        try:
            if scope["method"] == "POST":
                await exchange.read_body(self.max_body)
            await self.app(scope, exchange.receive, exchange.send)
        finally:
            ended = scope["method"] == "DELETE" and (exchange.status or 500) < 300
            if ended or exchange.status == 404:  # ended by its client, or already by the SDK
                self._open.pop(session.id, None)
            await self._finish(session, exchange, scope)

    async def _finish(self, session: _Session, exchange: _Exchange, scope: Scope) -> None:
        """A request of `session` is over: if its answer did not go out in full, the client
        dropped it; cancel its calls, and end the session when nothing else of it is open."""
        session.requests -= 1
        session.last_active = anyio.current_time()
        if exchange.answered:
            return
        with anyio.move_on_after(_OWN_REQUEST_TIMEOUT, shield=True):  # also while shutting down
            for request_id in exchange.request_ids():
                await self._cancel(session.id, request_id, scope)
            if session.requests == 0 and self._open.get(session.id) is session:
                await self._close(session.id, "its client dropped the connection")

    # -- sessions ------------------------------------------------------------------------------

    async def _reserve(self) -> bool:
        """Reserve a place for a new session, closing the least recently used idle session
        at the limit; False when every session has a request in flight."""
        if len(self._open) + self._opening >= self.limits.max_sessions:
            idle = [s for s in self._open.values() if s.requests == 0]
            if not idle:
                return False
            oldest = min(idle, key=lambda s: s.last_active)
            self._opening += 1  # before any await: a concurrent opening sees the place taken
            await self._close(oldest.id, f"the limit of {self.limits.max_sessions} was reached")
            return True
        self._opening += 1
        return True

    async def _expire_idle(self) -> None:
        idle_timeout = self.limits.idle_timeout
        while True:
            now = anyio.current_time()
            for session in list(self._open.values()):
                if session.requests == 0 and now - session.last_active >= idle_timeout:
                    await self._close(session.id, f"idle for {idle_timeout:g} s")
            # Any session that goes idle from now on is due no earlier than a full time-out.
            due = [s.last_active + idle_timeout for s in self._open.values() if s.requests == 0]
            await anyio.sleep(max(0.01, min(due, default=now + idle_timeout) - now))

    async def _close(self, session_id: str, reason: str) -> None:
        """End a session (its calls are cancelled): forgotten here at once, then DELETEd."""
        if self._open.pop(session_id, None) is None:
            return
        log.info("MCP session %s… closed: %s", session_id[:8], reason)
        await self._own_request("DELETE", session_id, None)

    async def _cancel(self, session_id: str, request_id: Any, scope: Scope) -> None:
        notice = {
            "jsonrpc": "2.0",
            "method": "notifications/cancelled",
            "params": {"requestId": request_id, "reason": "the client dropped the connection"},
        }
        log.info(
            "MCP session %s…: request %r dropped by its client, cancelled",
            session_id[:8],
            request_id,
        )
        await self._own_request("POST", session_id, notice, _headers(scope).get(VERSION_HEADER))

    async def _own_request(
        self, method: str, session_id: str, body: Any, version: str | None = None
    ) -> int | None:
        """Send the SDK app a request of this layer's own, as its client would; the status."""
        if self._template is None:
            return None
        data = json.dumps(body).encode() if body is not None else b""
        headers = [
            (b"host", _headers(self._template).get("host", "127.0.0.1").encode("latin-1")),
            (SESSION_HEADER.encode(), session_id.encode("latin-1")),
            (b"accept", b"application/json, text/event-stream"),
            (b"content-type", b"application/json"),
            (b"content-length", str(len(data)).encode()),
        ]
        if version is not None:
            headers.append((VERSION_HEADER.encode(), version.encode("latin-1")))
        scope = {
            **self._template,
            "method": method,
            "path": self.path,
            "raw_path": self.path.encode(),
            "query_string": b"",
            "headers": headers,
        }
        done = anyio.Event()
        status: list[int] = []
        sent = False

        async def receive() -> Message:
            nonlocal sent
            if not sent:
                sent = True
                return {"type": "http.request", "body": data, "more_body": False}
            await done.wait()
            return {"type": "http.disconnect"}

        async def send(message: Message) -> None:
            if message["type"] == "http.response.start":
                status.append(int(message["status"]))

        try:
            await self.app(scope, receive, send)
        except Exception:  # never in place of the request being finished (the server lives on)
            log.exception("MCP session %s…: %s of this server's own failed", session_id[:8], method)
        finally:
            done.set()
        return status[0] if status else None


async def _refuse(send: Send, limit: int, exchange: _Exchange) -> None:
    ids = exchange.request_ids()
    message = (
        f"too many MCP sessions: the limit is {limit} (shadowhound mcp --max-sessions) and "
        "every session has a request in flight; end a session (DELETE with its "
        "Mcp-Session-Id) or try again when one is idle"
    )
    log.warning("MCP session refused: %s", message)
    error = {
        "jsonrpc": "2.0",
        "id": ids[0] if ids else None,
        "error": {"code": -32000, "message": message},
    }
    await send_json(send, 503, error)


def _headers(scope: Scope) -> dict[str, str]:
    return {k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])}


def _header(message: Message, name: str) -> str | None:
    for key, value in message.get("headers", []):
        if key.decode("latin-1").lower() == name:
            return str(value.decode("latin-1"))
    return None


def _ignore(_message: Message) -> None:
    return None
