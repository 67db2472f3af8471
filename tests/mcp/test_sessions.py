"""MCP sessions over Streamable HTTP end soon after their clients: at once when the client drops
its connection, after `--session-idle` seconds idle, and the least recently used idle one when
`--max-sessions` would be passed (a new session is refused only while every session is busy).
A closed session's id answers 404. Real servers, raw HTTP clients."""

from __future__ import annotations

import subprocess

import pytest

from shadowhound.errors import ServeError
from shadowhound.mcp.limits import SessionLimits

from .conftest import server_command, server_env
from .wire import Wire

VERSION = "2025-11-25"


def opened(url: str) -> Wire:
    client = Wire(url, VERSION)
    client.initialize()
    return client


def status(client: Wire) -> int:
    """The status a request of the client's session gets: 200 while it is open, 404 after."""
    return client.send(client.tool_call("get_state", {})).status


def test_sessions_whose_clients_vanish_close_at_once(http_server):
    server = http_server("-v")  # the default idle time-out (minutes) plays no part here
    clients = [opened(server.url) for _ in range(5)]
    streams = [c.open_get_stream() for c in clients]
    assert all(status(c) == 200 for c in clients)
    for stream in streams:
        stream.close()  # the clients' processes end (a look meanwhile: a client still there)
    server.wait_for_log("closed: its client dropped the connection", count=5)
    assert [status(c) for c in clients] == [404] * 5
    assert status(opened(server.url)) == 200  # the server serves on


def test_an_idle_session_expires(http_server):
    # 3 s: the listening client must open its stream within that of opening its session (a few
    # milliseconds, more on a loaded machine), or it would be idle too.
    server = http_server("-v", "--session-idle", "3")
    client = opened(server.url)
    listening = opened(server.url)
    stream = listening.open_get_stream()  # a client that listens is never idle
    server.wait_for_log("closed: idle for 3 s")
    assert status(client) == 404
    assert status(listening) == 200
    stream.close()


def test_the_limit_closes_the_least_recently_used_idle_session(http_server):
    server = http_server("--max-sessions", "3")
    first, second, third = (opened(server.url) for _ in range(3))
    assert status(first) == 200  # first is now used more recently than second
    fourth = opened(server.url)
    assert status(second) == 404
    assert [status(c) for c in (first, third, fourth)] == [200, 200, 200]


def test_a_new_session_is_refused_while_every_session_is_busy(http_server):
    server = http_server("-v", "--max-sessions", "2")
    busy = [opened(server.url) for _ in range(2)]
    streams = [c.open_get_stream() for c in busy]
    late = Wire(server.url, VERSION)
    refused = late.send(late.initialize_body())
    assert refused.status == 503
    message = refused.messages[0]["error"]["message"]
    assert "too many MCP sessions: the limit is 2 (shadowhound mcp --max-sessions)" in message
    assert [status(c) for c in busy] == [200, 200]  # nobody was thrown out
    streams[0].close()  # that client is gone: its place frees at once
    server.wait_for_log("closed: its client dropped the connection")
    assert late.send(late.initialize_body()).status == 200
    streams[1].close()


@pytest.mark.parametrize(
    ("option", "value", "expected"),
    [
        ("--max-sessions", "0", "the session limit (--max-sessions) must be a whole number"),
        ("--session-idle", "0", "the session idle time-out (--session-idle) must be a number"),
        ("--session-idle", "inf", "the session idle time-out (--session-idle) must be a number"),
    ],
)
def test_bad_limits_are_refused_before_serving(option, value, expected):
    done = subprocess.run(
        server_command("--http", "--port", "0", option, value),
        env=server_env(),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert done.returncode == 2 and expected in done.stderr, done.stderr


def test_limits_say_what_is_allowed():
    with pytest.raises(ServeError, match="at least 1"):
        SessionLimits(max_sessions=0)
    with pytest.raises(ServeError, match="above 0"):
        SessionLimits(idle_timeout=-1)
    assert SessionLimits().idle_timeout > 60 and SessionLimits().max_sessions >= 8
