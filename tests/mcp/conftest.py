"""Fixtures for the MCP tests: `shadowhound mcp` as a separate process, reached with the SDK's
own client over stdio (the client starts the process) or Streamable HTTP (a server process on a
free 127.0.0.1 port)."""

from __future__ import annotations

import contextlib
import importlib.util
import os
import re
import subprocess
import sys
import threading
import time
from collections.abc import AsyncIterator, Callable, Iterator
from pathlib import Path
from typing import Any

import pytest

# Without the mcp extra these tests cannot run: skip the directory locally, fail in CI.
if importlib.util.find_spec("mcp") is None:
    if os.environ.get("CI") or os.environ.get("SHADOWHOUND_REQUIRE_ROS"):
        raise ImportError("the MCP tests need the 'mcp' extra (pip install -e '.[dev]')")
    collect_ignore_glob = ["test_*.py"]

SRC = str(Path(__file__).resolve().parents[2] / "src")
TOKEN = "mcp-test-token-0123456789abcdef"


def server_command(*extra: str, time_scale: float = 0.0) -> list[str]:
    return [sys.executable, "-m", "shadowhound", "mcp", "--time-scale", str(time_scale), *extra]


def server_env(**extra: str) -> dict[str, str]:
    """This checkout's package first; history in the session's temporary directory."""
    env = dict(os.environ)
    env["PYTHONPATH"] = SRC + os.pathsep + env.get("PYTHONPATH", "")
    env.pop("SHADOWHOUND_TOKEN", None)
    env.update(extra)
    return env


class HttpServer:
    """`shadowhound mcp --http` on a free loopback port, as its own process."""

    def __init__(self, *extra: str, time_scale: float = 0.0, env: dict[str, str] | None = None):
        self.proc = subprocess.Popen(
            server_command("--http", "--port", "0", *extra, time_scale=time_scale),
            env=env or server_env(),
            stdout=subprocess.DEVNULL,
            stderr=subprocess.PIPE,
            text=True,
        )
        self.url = self._wait_for_url()
        # The rest of stderr is read on a thread: the pipe never fills, and tests can wait for
        # a log line (start the server with "-v" for the INFO ones).
        self.log: list[str] = []
        self._logged = threading.Condition()
        threading.Thread(target=self._read_log, daemon=True).start()

    def _read_log(self) -> None:
        assert self.proc.stderr is not None
        for line in self.proc.stderr:
            with self._logged:
                self.log.append(line)
                self._logged.notify_all()

    def wait_for_log(self, text: str, count: int = 1, timeout: float = 60.0) -> None:
        """Until `count` lines of the server's log contain `text`."""
        with self._logged:
            if not self._logged.wait_for(
                lambda: sum(text in line for line in self.log) >= count, timeout
            ):
                raise AssertionError(f"{count} x {text!r} not logged: {''.join(self.log)[-2000:]}")

    def _wait_for_url(self) -> str:
        assert self.proc.stderr is not None
        seen = []
        deadline = time.monotonic() + 120  # a loaded machine starts Python slowly
        while time.monotonic() < deadline:
            line = self.proc.stderr.readline()
            if not line:
                break
            seen.append(line)
            match = re.search(r"(http://\S+/mcp)", line)
            if match:
                return match.group(1)
        self.stop()
        raise RuntimeError("the MCP server did not start: " + "".join(seen)[-2000:])

    def alive(self) -> bool:
        return self.proc.poll() is None

    def stop(self) -> None:
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(30)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait()


@pytest.fixture
def http_server() -> Iterator[Callable[..., HttpServer]]:
    """Start HTTP servers (stopped after the test): `http_server(time_scale=1.0)`."""
    started: list[HttpServer] = []

    def start(*extra: str, **kwargs: Any) -> HttpServer:
        server = HttpServer(*extra, **kwargs)
        started.append(server)
        return server

    yield start
    for server in started:
        server.stop()


@contextlib.asynccontextmanager
async def connect(
    transport: str,
    *,
    time_scale: float = 0.0,
    url: str | None = None,
    server_args: tuple[str, ...] = (),
    **client_options: Any,
) -> AsyncIterator[Any]:
    """An SDK `Client` on a new server process (stdio, with `server_args`) or on `url` (HTTP)."""
    from mcp import Client
    from mcp.client.stdio import StdioServerParameters

    if transport == "stdio":
        target: Any = StdioServerParameters(
            command=sys.executable,
            args=server_command(*server_args, time_scale=time_scale)[1:],
            env=server_env(),
        )
    else:
        assert url is not None
        target = url
    async with Client(target, read_timeout_seconds=60, **client_options) as client:
        yield client


def structured(result: Any) -> dict[str, Any]:
    assert result.structured_content is not None, result.content
    return dict(result.structured_content)


def text_of(result: Any) -> str:
    return " ".join(getattr(c, "text", "") for c in result.content)
