"""The web dashboard and HTTP API (the `web` extra: FastAPI and uvicorn).

    from shadowhound.web import create_app, WebServer
    app = create_app(agent)                 # FastAPI app: page, /api/..., /ws/status
    server = WebServer(app, port=8080).start(); ...; server.stop()

`serve_main(settings, host, port, token)` is what `shadowhound serve` calls. Importing
`shadowhound` never imports this package; importing this package does not import FastAPI
until `create_app`, `serve` or `WebServer` is used, so a missing extra gets a clear message.
"""

from __future__ import annotations

import os
import sys
from typing import TYPE_CHECKING, Any

from ..exit_codes import EXIT_USAGE

if TYPE_CHECKING:
    from ..config import ShadowHoundConfig
    from .app import create_app
    from .server import WebServer, serve

__all__ = ["WebServer", "create_app", "serve", "serve_main"]

_LAZY = {"create_app": "app", "serve": "server", "WebServer": "server"}


def __getattr__(name: str) -> Any:
    if name in _LAZY:
        from importlib import import_module

        return getattr(import_module(f".{_LAZY[name]}", __name__), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")


def serve_main(
    settings: ShadowHoundConfig, host: str = "127.0.0.1", port: int = 8080, token: str | None = None
) -> int:
    """`shadowhound serve`: run the dashboard until Ctrl-C. Returns the exit code.

    `token` defaults to $SHADOWHOUND_TOKEN. Returns 2 (with a message on stderr) when the web
    extra is missing, the port is taken, or a non-loopback host has no token.
    """
    try:
        from .server import serve
    except ModuleNotFoundError as exc:
        print(
            f"shadowhound serve: the web dashboard needs the 'web' extra ({exc.name} is not "
            "installed): pip install 'shadowhound[web]'",
            file=sys.stderr,
        )
        return EXIT_USAGE
    return serve(settings, host, port, token or os.environ.get("SHADOWHOUND_TOKEN") or None)
