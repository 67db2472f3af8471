"""The MCP server's HTTP gate: loopback without a token, a token beyond it, no foreign Origin
(DNS rebinding), checked in-process for every kind of header (hypothesis) and on a real server."""

from __future__ import annotations

import asyncio
import subprocess
import sys
from typing import Any

import httpx
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound.mcp.transport import McpGate

from .conftest import TOKEN, server_env, structured

INIT = {
    "jsonrpc": "2.0",
    "id": 1,
    "method": "initialize",
    "params": {
        "protocolVersion": "2025-11-25",
        "capabilities": {},
        "clientInfo": {"name": "test", "version": "0"},
    },
}
LOOPBACK = {"127.0.0.1", "localhost", "::1"}


def _call_gate(gate_token: str | None, headers: dict[str, str]) -> tuple[int, bool]:
    """(status, whether the MCP app behind the gate was reached)."""
    reached: list[bool] = []
    sent: list[dict[str, Any]] = []

    async def app(scope: Any, receive: Any, send: Any) -> None:
        reached.append(True)
        await send({"type": "http.response.start", "status": 200, "headers": []})
        await send({"type": "http.response.body", "body": b""})

    async def send(message: dict[str, Any]) -> None:
        sent.append(message)

    async def receive() -> dict[str, Any]:
        return {"type": "http.request", "body": b"", "more_body": False}

    scope = {
        "type": "http",
        "method": "POST",
        "path": "/mcp",
        "headers": [(k.lower().encode("latin-1"), v.encode("latin-1")) for k, v in headers.items()],
    }
    gate = McpGate(app, gate_token, set(LOOPBACK))
    asyncio.run(gate(scope, receive, send))
    return sent[0]["status"], bool(reached)


header_text = st.text(st.characters(min_codepoint=33, max_codepoint=126), max_size=40)


@settings(max_examples=150, deadline=None)
@given(host=header_text)
def test_without_a_token_only_loopback_host_names_reach_the_server(host):
    status, reached = _call_gate(None, {"host": host})
    name = (
        host.lower().rsplit(":", 1)[0]
        if not host.startswith("[")
        else host.lower()[1:].split("]")[0]
    )
    if reached:
        assert name in LOOPBACK, host
    else:
        assert status == 421


@settings(max_examples=150, deadline=None)
@given(
    origin=st.one_of(
        header_text,
        st.sampled_from(
            [
                "http://127.0.0.1:8765",
                "https://127.0.0.1:8765",
                "HTTP://127.0.0.1:8765",
                "http://127.0.0.1:8766",
                "http://localhost:8765",
                "null",
                "ftp://127.0.0.1:8765",
                "http://127.0.0.1:8765.evil.example",
                "http://evil.example/127.0.0.1:8765",
            ]
        ),
    ),
    token=st.sampled_from([None, TOKEN]),
)
def test_a_foreign_origin_never_reaches_the_server(origin, token):
    headers = {"host": "127.0.0.1:8765", "origin": origin}
    if token:
        headers["authorization"] = f"Bearer {token}"
    status, reached = _call_gate(token, headers)
    assert reached == (origin.lower() in ("http://127.0.0.1:8765", "https://127.0.0.1:8765"))
    if not reached:
        assert status == 403


@settings(max_examples=150, deadline=None)
@given(offered=header_text, host=st.sampled_from(["127.0.0.1:1", "robot.example:8765"]))
def test_with_a_token_nothing_else_opens_the_server(offered, host):
    status, reached = _call_gate(TOKEN, {"host": host, "authorization": f"Bearer {offered}"})
    assert reached == (offered == TOKEN)
    if not reached:
        assert status == 401
    assert _call_gate(TOKEN, {"host": host, "authorization": f"Bearer {TOKEN}"}) == (200, True)


def test_a_dns_rebinding_page_is_refused_by_the_real_server(http_server):
    server = http_server()
    port = server.url.split(":")[2].split("/")[0]
    headers = {"content-type": "application/json", "accept": "application/json, text/event-stream"}
    rebound = httpx.post(
        server.url,
        json=INIT,
        timeout=30,
        headers={
            **headers,
            "host": f"attacker.example:{port}",
            "origin": f"http://attacker.example:{port}",
        },
    )
    assert rebound.status_code == 421 and "loopback" in rebound.text
    foreign = httpx.post(
        server.url, json=INIT, timeout=30, headers={**headers, "origin": "http://evil.example"}
    )
    assert foreign.status_code == 403
    own = httpx.post(server.url, json=INIT, timeout=30, headers=headers)
    assert own.status_code == 200


def test_listening_beyond_loopback_needs_a_strong_token():
    proc = subprocess.run(
        [sys.executable, "-m", "shadowhound", "mcp", "--http", "--host", "0.0.0.0", "--port", "0"],
        env=server_env(),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert proc.returncode == 2
    assert "beyond loopback the MCP server needs a token" in proc.stderr
    weak = subprocess.run(
        [
            sys.executable,
            "-m",
            "shadowhound",
            "mcp",
            "--http",
            "--host",
            "0.0.0.0",
            "--port",
            "0",
            "--token",
            "short",
        ],
        env=server_env(),
        capture_output=True,
        text=True,
        timeout=60,
    )
    assert weak.returncode == 2 and "at least 16" in weak.stderr


def test_a_token_server_answers_only_clients_with_the_token(http_server):
    import httpx2
    from mcp.client.streamable_http import streamable_http_client

    server = http_server("--token", TOKEN)
    refused = httpx.post(
        server.url,
        json=INIT,
        timeout=30,
        headers={
            "content-type": "application/json",
            "accept": "application/json, text/event-stream",
        },
    )
    assert refused.status_code == 401

    async def scenario() -> dict[str, Any]:
        from mcp import Client

        http = httpx2.AsyncClient(headers={"authorization": f"Bearer {TOKEN}"})
        async with (
            http,
            Client(
                streamable_http_client(server.url, http_client=http), read_timeout_seconds=60
            ) as client,
        ):
            return structured(await client.call_tool("get_state", {}))

    assert asyncio.run(scenario())["robot"]["connected"] is True
