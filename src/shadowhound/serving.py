"""Exposing a server on the network, the same for the web dashboard and the MCP server.

- Without a token, a server listens only on loopback: a literal loopback address
  (127.0.0.0/8, ::1) or the name `localhost`; any other name counts as remote, unresolved.
- Beyond loopback it needs a token of at least MIN_TOKEN_CHARS URL-safe characters.
- `hostname` reads a Host header strictly, for the servers' DNS-rebinding checks.
- `bind` makes the listening socket (TCP_NODELAY-ready), or says why it cannot.
- `settle_heap` keeps the garbage collector's full passes short in a long-running server.
Standard library only.
"""

from __future__ import annotations

import gc
import ipaddress
import re
import socket
from collections.abc import Awaitable, Callable
from typing import Any

from . import jsonout
from .errors import ServeError

LOOPBACK_HOSTS = ("127.0.0.1", "localhost", "::1")

MIN_TOKEN_CHARS = 16
_TOKEN_HINT = (
    "for example: export SHADOWHOUND_TOKEN=$(python3 -c "
    "'import secrets; print(secrets.token_urlsafe(24))')"
)


def check_binding(host: str, token: str | None, what: str = "the dashboard") -> None:
    """Refuse to listen beyond loopback without a strong enough token. Raises ServeError."""
    if not is_loopback(host) and not token:
        raise ServeError(
            f"refusing to listen on {host}: only a literal loopback address "
            "(127.x.x.x, ::1) or localhost counts as loopback (names are not "
            f"resolved), and beyond loopback {what} needs a token; set "
            "SHADOWHOUND_TOKEN or pass --token, " + _TOKEN_HINT
        )
    if token is not None and len(token) < MIN_TOKEN_CHARS:
        raise ServeError(
            f"the token is {len(token)} characters long; use at least "
            f"{MIN_TOKEN_CHARS}, " + _TOKEN_HINT
        )
    if token is not None and not all(c.isalnum() or c in "-._~" for c in token):
        raise ServeError(
            "the token may contain only letters, digits and - . _ ~ (it travels "
            "in headers, URLs and WebSocket subprotocols), " + _TOKEN_HINT
        )


def is_loopback(host: str) -> bool:
    """True for a literal loopback address (127.0.0.0/8, ::1) or the name `localhost`.

    Any other name counts as remote without resolving it: `127.attacker.example` is a name
    like any other, and what a name resolves to can change after the check.
    """
    name = host.strip().lower()
    if name.startswith("[") and name.endswith("]"):
        name = name[1:-1]
    if name == "localhost":
        return True
    try:
        return ipaddress.ip_address(name).is_loopback
    except ValueError:
        return False


# RFC 9110 Host: uri-host [ ":" port ]; an IP literal in brackets, else a registered name.
_HOST = re.compile(r"(?:\[(?P<v6>[0-9a-f:.]+)\]|(?P<name>[a-z0-9._~-]+))(?::(?P<port>[0-9]{0,5}))?")


def hostname(host: str) -> str | None:
    """The host name of a Host header value, lower case; None when the value is not one."""
    match = _HOST.fullmatch(host.strip().lower())
    if match is None or (match["port"] and int(match["port"]) > 65535):
        return None
    return match["v6"] or match["name"]


def bind(host: str, port: int) -> socket.socket:
    """A listening socket (port 0 picks a free one). Raises ServeError when it cannot."""
    family = socket.AF_INET6 if ":" in host else socket.AF_INET
    # IPPROTO_TCP explicitly: asyncio sets TCP_NODELAY only on connections whose socket says
    # TCP, and without it a streamed answer waits ~40 ms for the client's delayed ACK (Nagle).
    sock = socket.socket(family, socket.SOCK_STREAM, socket.IPPROTO_TCP)
    try:
        sock.setsockopt(socket.SOL_SOCKET, socket.SO_REUSEADDR, 1)
        sock.bind((host, port))
        sock.listen(128)
    except (OSError, OverflowError) as exc:  # OverflowError: a port outside 0-65535
        sock.close()
        why = getattr(exc, "strerror", None) or str(exc)
        raise ServeError(f"cannot listen on {host}:{port}: {why}") from exc
    sock.set_inheritable(True)
    return sock


async def send_json(
    send: Callable[[dict[str, Any]], Awaitable[None]],
    status: int,
    payload: object,
    headers: list[tuple[bytes, bytes]] | None = None,
) -> None:
    """Answer an ASGI request with `payload` as JSON, before any app sees it (the security
    gates of the dashboard and the MCP server). Strict JSON: see jsonout."""
    body = jsonout.dumps(payload).encode()
    await send(
        {
            "type": "http.response.start",
            "status": status,
            "headers": [
                (b"content-type", b"application/json"),
                (b"content-length", str(len(body)).encode()),
                *(headers or []),
            ],
        }
    )
    await send({"type": "http.response.body", "body": body})


def settle_heap() -> None:
    """Call once a server has started: move what startup built (modules, classes, the app,
    the robot; some 70,000 objects with FastAPI) out of the garbage collector's reach.

    A full collection walks every tracked object and holds the interpreter meanwhile: about
    50 ms on this project's 2-core machine, during which no e-stop is answered and no control
    tick runs. Startup objects live as long as the process, so the collector need not walk
    them again (`gc.freeze`); with them frozen a full pass takes about 2 ms.
    """
    gc.collect()
    gc.freeze()
