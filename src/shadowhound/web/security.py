"""The web app's gate: token, host and origin checks, and a body size limit (one ASGI layer).

- Token (when one is configured): `Authorization: Bearer <token>` on every /api/ and /ws/
  request except `GET /api/health`. Browsers cannot set headers on EventSource, <img> or
  WebSocket, so GET requests and WebSockets may give `?token=` instead, and WebSockets may
  offer the subprotocol `bearer.<token>` (next to `shadowhound`). Mutating requests need the
  header, so a token never has to travel in a URL to move the robot.
- Host (without a token): only loopback names, so a web page cannot reach the robot through
  DNS rebinding. The header is parsed strictly (`name`, `name:port`, `[v6]`, `[v6]:port`, the
  port all digits); anything else, such as `127.0.0.1:8080.evil.example`, is refused.
- Origin: a request that changes something, and every WebSocket, must come from the page's own
  origin, scheme and host and port alike (no cross-site requests; there is no CORS at all): an
  `https://` origin is not the page of a server answering http, which a TLS proxy in front
  says with `X-Forwarded-Proto` (uvicorn reads it from a proxy on loopback).
- Bodies over `max_body` bytes get 413 before any route sees them, and a body that does not
  arrive within `BODY_SECONDS` gets 408 (a client trickling bytes holds nothing for long);
  `limits` give a path its own size and time (a recording: `speech.max_bytes`,
  `speech.upload_timeout`).
- Secrets (the token, the model's API key) are masked in every JSON answer, whatever put them
  there (an error message quoting a URL, say).

Where a server may listen, with what token, and its socket: `shadowhound.serving`, the same
for the dashboard and the MCP server.
"""

from __future__ import annotations

import asyncio
import hmac
import os
import sys
from collections.abc import Awaitable, Callable, Iterable, Mapping, MutableMapping
from dataclasses import dataclass
from typing import Any
from urllib.parse import parse_qs, urlsplit

from ..serving import hostname, send_json

Scope = MutableMapping[str, Any]
Message = MutableMapping[str, Any]
Receive = Callable[[], Awaitable[Message]]
Send = Callable[[Message], Awaitable[None]]
ASGIApp = Callable[[Scope, Receive, Send], Awaitable[None]]

WS_PROTOCOL = "shadowhound"
GONE = 499  # _read_body: the client disconnected before its body came (never sent)
BODY_SECONDS = 10.0  # a JSON body is a few kB: on any link it arrives well within this
SAFE_METHODS = {"GET", "HEAD", "OPTIONS"}
OPEN_PATHS = {"/api/health"}
_HEADERS = [
    (b"x-content-type-options", b"nosniff"),
    (b"x-frame-options", b"DENY"),
    (b"referrer-policy", b"no-referrer"),
]


@dataclass(frozen=True)
class BodyLimit:
    """How large a request body may be and how long it may take to arrive, and what to say
    when one is over either."""

    max_bytes: int
    too_big: str
    seconds: float = BODY_SECONDS
    too_slow: str = ""

    def slow(self) -> str:
        return self.too_slow or f"the request body did not arrive within {self.seconds:g} s"


def secret_values(token: str | None, api_key_env: str | None = None) -> list[str]:
    """Values that must never appear in an answer: the token and the model's API key."""
    values = [token] if token else []
    key = os.environ.get(api_key_env) if api_key_env else None
    if key and len(key) >= 8:  # a short value would mask ordinary words
        values.append(key)
    return values


def scrubber(secrets: Iterable[str]) -> Callable[[str], str]:
    masked = [s for s in secrets if s]

    def scrub(text: str) -> str:
        for secret in masked:
            if secret in text:
                text = text.replace(secret, "***")
        return text

    return scrub


class Gate:
    """ASGI middleware applying the checks above to HTTP requests and WebSockets."""

    def __init__(
        self,
        app: ASGIApp,
        *,
        token: str | None,
        allowed_hosts: Iterable[str] | None,
        max_body: int,
        secrets: Iterable[str] = (),
        limits: Mapping[str, BodyLimit] | None = None,
    ) -> None:
        """`limits`: paths whose bodies have a limit of their own (a recording)."""
        self.app = app
        self.limits = dict(limits or {})
        self.secrets = [s.encode() for s in secrets if s]
        self.token = token
        self.allowed_hosts = None if allowed_hosts is None else {h.lower() for h in allowed_hosts}
        self.max_body = max_body
        self.body_limit = BodyLimit(
            max_body, f"the request body is larger than {max_body} bytes", BODY_SECONDS
        )

    async def __call__(self, scope: Scope, receive: Receive, send: Send) -> None:
        if scope["type"] not in ("http", "websocket"):
            await self.app(scope, receive, send)
            return
        headers = {
            k.decode("latin-1").lower(): v.decode("latin-1") for k, v in scope.get("headers", [])
        }
        problem = self._check(scope, headers)
        if problem is not None:
            await self._refuse(scope, receive, send, *problem)
            return
        if scope["type"] == "http" and scope["method"] not in SAFE_METHODS:
            limit = self.limits.get(scope.get("path", ""), self.body_limit)
            body = await _read_body(receive, headers, limit)
            if body == GONE:
                return
            if isinstance(body, int):  # the rest of the body is never read: close after
                said = limit.too_big if body == 413 else limit.slow()
                await _send_json(send, body, said, [(b"connection", b"close")])
                return
            receive = _replay(body, receive)
        if scope["type"] == "http":
            send = self._guard_send(send)
        await self.app(scope, receive, send)

    def _guard_send(self, send: Send) -> Send:
        """Add protective headers; mask secrets in JSON bodies (buffered: they are small)."""
        start: Message | None = None
        chunks: list[bytes] = []

        async def guarded(message: Message) -> None:
            nonlocal start
            if message["type"] == "http.response.start":
                message["headers"] = [*message.get("headers", []), *_HEADERS]
                ctype = dict(message["headers"]).get(b"content-type", b"")
                if self.secrets and ctype.startswith(b"application/json"):
                    start = message  # held until the body is known
                    return
            elif message["type"] == "http.response.body" and start is not None:
                chunks.append(message.get("body", b""))
                if message.get("more_body", False):
                    return
                body = b"".join(chunks)
                for secret in self.secrets:
                    body = body.replace(secret, b"***")
                start["headers"] = [(k, v) for k, v in start["headers"] if k != b"content-length"]
                start["headers"].append((b"content-length", str(len(body)).encode()))
                await send(start)
                message = {"type": "http.response.body", "body": body}
            await send(message)

        return guarded

    def _check(self, scope: Scope, headers: dict[str, str]) -> tuple[int, str] | None:
        host = hostname(headers.get("host", ""))
        if (
            self.allowed_hosts is not None
            and self.token is None
            and (host is None or host not in self.allowed_hosts)
        ):
            shown = host if host is not None else headers.get("host", "")[:100]
            return 400, (
                f"host {shown!r} is not allowed: without a token the dashboard answers "
                "only on loopback names (set a token to serve other hosts)"
            )
        websocket = scope["type"] == "websocket"
        origin = headers.get("origin")
        if origin is not None and (websocket or scope["method"] not in SAFE_METHODS):
            parts = urlsplit(origin)
            if parts.netloc.lower() != headers.get(
                "host", ""
            ).lower() or parts.scheme.lower() != _page_scheme(scope):
                return 403, "cross-origin requests are not allowed; use the dashboard's own page"
        path = scope.get("path", "")
        if self.token is None or path in OPEN_PATHS or not path.startswith(("/api/", "/ws/")):
            return None
        if self._token_ok(scope, headers, websocket):
            return None
        return 401, (
            "a valid token is required: send 'Authorization: Bearer <token>' "
            "(GET requests and WebSockets may use ?token=<token>)"
        )

    def _token_ok(self, scope: Scope, headers: dict[str, str], websocket: bool) -> bool:
        assert self.token is not None
        offered: list[str] = []
        auth = headers.get("authorization", "")
        if auth[:7].lower() == "bearer ":
            offered.append(auth[7:].strip())
        if websocket or scope.get("method") in SAFE_METHODS:
            query = parse_qs(scope.get("query_string", b"").decode("latin-1"))
            offered += query.get("token", [])[:1]
        if websocket:
            offered += [
                p[len("bearer.") :]
                for p in scope.get("subprotocols", [])
                if p.startswith("bearer.")
            ][:1]
        expected = self.token.encode()
        return any(hmac.compare_digest(o.encode(), expected) for o in offered)

    async def _refuse(
        self, scope: Scope, receive: Receive, send: Send, status: int, detail: str
    ) -> None:
        if scope["type"] == "websocket":
            await receive()  # websocket.connect
            await send({"type": "websocket.close", "code": 1008, "reason": detail[:120]})
            return
        extra = [(b"www-authenticate", b"Bearer")] if status == 401 else []
        await _send_json(send, status, detail, extra)


def _page_scheme(scope: Scope) -> str:
    """The scheme of the page this server serves: http or https (a WebSocket's ws or wss)."""
    scheme = str(scope.get("scheme", "http")).lower()
    return {"ws": "http", "wss": "https"}.get(scheme, scheme)


async def _read_body(
    receive: Receive, headers: dict[str, str], limit: BodyLimit
) -> list[Message] | int:
    """Every body message, or the status to refuse it with: 413 once it passes the limit's
    bytes, 408 when it has not all come within the limit's seconds; GONE when the client went
    away first."""
    declared = headers.get("content-length", "")
    if declared.isdigit() and int(declared) > limit.max_bytes:
        return 413
    try:  # one timer for the whole body, in the request's own task (no task more)
        if sys.version_info >= (3, 11):
            async with asyncio.timeout(limit.seconds):
                return await _collect(receive, limit.max_bytes)
        return await asyncio.wait_for(_collect(receive, limit.max_bytes), limit.seconds)
    except asyncio.TimeoutError:
        return 408


async def _collect(receive: Receive, max_bytes: int) -> list[Message] | int:
    messages, size = [], 0
    while True:
        message = await receive()
        if message["type"] != "http.request":
            return GONE  # the client went away before its body came: nobody to answer
        messages.append(message)
        size += len(message.get("body", b""))
        if size > max_bytes:
            return 413
        if not message.get("more_body", False):
            return messages


def _replay(messages: list[Message], receive: Receive) -> Receive:
    pending = list(messages)

    async def replay() -> Message:
        return pending.pop(0) if pending else await receive()

    return replay


async def _send_json(
    send: Send, status: int, detail: str, headers: list[tuple[bytes, bytes]] | None = None
) -> None:
    await send_json(send, status, {"detail": detail}, headers)
