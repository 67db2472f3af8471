"""Listening sockets made by `bind` (the MCP server's and the dashboard's) give every accepted
connection TCP_NODELAY, so a streamed answer (Server-Sent Events) is not held back by Nagle's
algorithm until the client's delayed ACK."""

from __future__ import annotations

import asyncio
import importlib
import socket

import pytest


@pytest.mark.parametrize("module", ["shadowhound.mcp.transport", "shadowhound.web.server"])
def test_accepted_connections_send_without_delay(module):
    bind = importlib.import_module(module).bind

    async def scenario() -> int:
        seen: asyncio.Queue[int] = asyncio.Queue()

        async def accepted(_reader: asyncio.StreamReader, writer: asyncio.StreamWriter) -> None:
            conn = writer.get_extra_info("socket")
            await seen.put(conn.getsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY))
            writer.close()

        sock = bind("127.0.0.1", 0)
        server = await asyncio.start_server(accepted, sock=sock)
        async with server:
            _reader, writer = await asyncio.open_connection(*sock.getsockname()[:2])
            value = await asyncio.wait_for(seen.get(), 60)
            writer.close()
        return value

    assert asyncio.run(scenario()) != 0
