"""Running the app with uvicorn: `serve()` in the foreground (the CLI) or `WebServer` in a
background thread (the ROS node, tests, benchmarks)."""

from __future__ import annotations

import logging
import signal
import sys
import threading
import time
from collections.abc import Iterable
from typing import Any

import uvicorn
from fastapi import FastAPI

from ..agent import RobotAgent
from ..config import ShadowHoundConfig
from ..errors import ConfigError, ServeError
from ..exit_codes import EXIT_OK, EXIT_USAGE
from ..serving import LOOPBACK_HOSTS, MIN_TOKEN_CHARS, bind, check_binding, settle_heap
from .app import create_app

__all__ = [
    "MIN_TOKEN_CHARS",
    "ServeError",
    "WebServer",
    "bind",
    "check_binding",
    "hosts_for",
    "serve",
]

log = logging.getLogger(__name__)


def hosts_for(host: str) -> list[str]:
    """Host names the app answers to without a token: loopback and the one it binds."""
    return [*LOOPBACK_HOSTS, host] if host not in ("0.0.0.0", "::") else list(LOOPBACK_HOSTS)


def _config(app: FastAPI, log_level: str) -> uvicorn.Config:
    # No access log: GET requests from the page may carry ?token= in their URL.
    # No permessage-deflate: with it every event is compressed once per WebSocket client (a
    # compressor each), which made the fan-out to 200 clients cost the server half as much
    # again as to 200 event-stream clients; the events are small JSON on a local network.
    return uvicorn.Config(
        app,
        log_level=log_level,
        access_log=False,
        lifespan="on",
        timeout_graceful_shutdown=2,
        ws_ping_interval=20,
        ws_per_message_deflate=False,
    )


class _StopFirst(uvicorn.Server):
    """uvicorn's server; an exit signal (Ctrl-C, SIGTERM) also e-stops the robot at once.

    uvicorn's graceful shutdown waits up to 2 s for open event streams before the app ends, and
    a mission would walk on meanwhile. The stop runs on a thread that waits for the signal: the
    handler itself interrupts the event loop's thread anywhere, even inside the agent's locks.
    """

    def __init__(self, config: uvicorn.Config, stop: Any) -> None:
        super().__init__(config)
        self._asked = threading.Event()
        self._stop = stop
        self._done = False
        threading.Thread(target=self._stop_when_asked, name="shadowhound-stop", daemon=True).start()

    def _stop_when_asked(self) -> None:
        self._asked.wait()
        if not self._done:
            self._stop()

    def handle_exit(self, sig: int, frame: Any) -> None:
        self._asked.set()
        super().handle_exit(sig, frame)

    def finish(self) -> None:
        """The server has ended: let the waiting thread go without stopping anything."""
        self._done = True
        self._asked.set()


class WebServer:
    """Runs an app in a background thread: `start()` returns once it accepts connections."""

    def __init__(
        self, app: FastAPI, host: str = "127.0.0.1", port: int = 0, log_level: str = "warning"
    ) -> None:
        self.app = app
        self._sock = bind(host, port)
        self.host, self.port = self._sock.getsockname()[:2]
        self._server = uvicorn.Server(_config(app, log_level))
        self._thread = threading.Thread(target=self._run, name="shadowhound-web", daemon=True)

    @property
    def url(self) -> str:
        host = f"[{self.host}]" if ":" in self.host else self.host
        return f"http://{host}:{self.port}"

    def start(self, timeout: float = 10.0) -> WebServer:
        self._thread.start()
        deadline = time.monotonic() + timeout
        while not self._server.started:
            if not self._thread.is_alive() or time.monotonic() > deadline:
                raise ServeError(f"the web server did not start within {timeout:g} s")
            time.sleep(0.01)
        return self

    def stop(self, timeout: float = 5.0) -> None:
        self._server.should_exit = True
        self._thread.join(timeout)
        self._sock.close()

    def _run(self) -> None:
        self._server.run(sockets=[self._sock])


def serve(
    settings: ShadowHoundConfig,
    host: str = "127.0.0.1",
    port: int = 8080,
    token: str | None = None,
    *,
    agent: RobotAgent | None = None,
    allowed_hosts: Iterable[str] | None = None,
    log_level: str = "warning",
    out: Any = None,
) -> int:
    """Run the dashboard until Ctrl-C or SIGTERM. Returns an exit code (0 after a stop, 2 when
    it cannot start).

    The simulated robot runs in real time here: a time scale of 0 would finish a mission before
    the page could show it, so 0 (the profiles' default) becomes 1.
    """
    out = out or sys.stderr
    token = token or None
    try:
        check_binding(host, token)
        if agent is None:
            if settings.robot.type == "sim" and settings.sim.time_scale == 0:
                sim = settings.sim.model_copy(update={"time_scale": 1.0})
                settings = settings.model_copy(update={"sim": sim})
            agent = RobotAgent(settings)
        agent.initialize()
        sock = bind(host, port)
    except (ServeError, ConfigError) as exc:
        print(f"shadowhound serve: {exc}", file=out)
        return EXIT_USAGE
    app = create_app(
        agent,
        token=token,
        allowed_hosts=hosts_for(host) if allowed_hosts is None else allowed_hosts,
    )
    shown = f"[{host}]" if ":" in host else host
    print(
        f"ShadowHound dashboard on http://{shown}:{sock.getsockname()[1]}/ (robot "
        f"{agent.robot.name}, backend {agent.settings.backend}"
        + (", token required" if token else "")
        + "); Ctrl-C stops",
        file=out,
        flush=True,
    )
    # uvicorn shuts down gracefully on SIGINT/SIGTERM and then raises the signal again with
    # the previous handlers; make SIGTERM an exception too so the robot is always released.
    main = threading.current_thread() is threading.main_thread()
    previous = signal.signal(signal.SIGTERM, _raise_interrupt) if main else None
    server = _StopFirst(_config(app, log_level), agent.estop)
    settle_heap()  # a long-running server: keep full collections short (serving.py)
    try:
        server.run(sockets=[sock])
    except KeyboardInterrupt:
        print("shadowhound serve: stopped; the robot is stopped", file=out)
    finally:
        server.finish()
        if main:
            signal.signal(signal.SIGTERM, previous)
        agent.cleanup()
        sock.close()
    return EXIT_OK


def _raise_interrupt(_signum: int, _frame: Any) -> None:
    raise KeyboardInterrupt
