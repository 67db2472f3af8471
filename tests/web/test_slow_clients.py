"""Against a real uvicorn server on 127.0.0.1: a client that does not read never slows the
others, is told it fell behind, and is disconnected; a client that keeps up loses nothing."""

from __future__ import annotations

import base64
import json
import os
import socket
import threading
import time
from collections.abc import Callable
from typing import Any

import httpx

from shadowhound.web import WebServer
from tests.web.conftest import SAFETY, make_agent, wait_for

Serve = Callable[..., WebServer]
# 1500 events of 10 kB: 15 MB, more than socket buffers hold (Linux grows a loopback sender's
# buffer up to 4 MB)
EVENTS, CHUNK = 1500, 100
PAD = "x" * 10_000


class FastReader(threading.Thread):
    """Reads /api/events as fast as it comes; remembers every numbered message."""

    def __init__(self, url: str) -> None:
        super().__init__(daemon=True)
        self.url = url
        self.seqs: list[int] = []
        self.kinds: list[str] = []
        self.ready = threading.Event()
        self.stop = threading.Event()

    def run(self) -> None:
        try:
            self._read()
        except httpx.HTTPError:
            if not self.stop.is_set():  # the server went away before the test ended
                raise

    def _read(self) -> None:
        with (
            httpx.Client(timeout=SAFETY) as client,
            client.stream("GET", self.url + "/api/events") as stream,
        ):
            for line in stream.iter_lines():
                if line.startswith("data: "):
                    message = json.loads(line[6:])
                    self.kinds.append(message["kind"])
                    if message["kind"] == "snapshot":
                        self.ready.set()
                    elif message["seq"] is not None:
                        self.seqs.append(message["seq"])
                if self.stop.is_set():
                    return


def _publish_keeping_pace(feed: Any, reader: FastReader) -> list[int]:
    """Publish EVENTS events in chunks, each once the fast reader has the previous one."""
    published: list[int] = []
    for _ in range(EVENTS // CHUNK):
        for _ in range(CHUNK):
            published.append(feed.publish("step", {"pad": PAD})["seq"])
        last = published[-1]
        wait_for(
            lambda last=last: reader.seqs and reader.seqs[-1] >= last,
            what="the fast client to read the chunk",
        )
    return published


def _slow_socket(server: WebServer, request: bytes) -> socket.socket:
    sock = socket.socket()
    sock.setsockopt(socket.SOL_SOCKET, socket.SO_RCVBUF, 4096)  # a small window: fills quickly
    sock.connect((server.host, server.port))
    sock.sendall(request)
    return sock


def _read_all(sock: socket.socket, timeout: float = 60.0) -> bytes:
    """Everything up to the end of the chunked body (the server ended the stream)."""
    sock.settimeout(timeout)
    deadline = time.monotonic() + timeout
    data = b""
    while not data.endswith(b"0\r\n\r\n"):
        if time.monotonic() > deadline:
            raise AssertionError(f"the stream did not end; it ends with {data[-300:]!r}")
        chunk = sock.recv(1 << 16)
        if not chunk:
            break
        data += chunk
    return data


def test_a_slow_sse_client_is_told_and_dropped_while_a_fast_one_gets_everything(
    serve: Serve,
) -> None:
    server = serve(make_agent())
    feed = server.app.state.web.feed
    fast = FastReader(server.url)
    fast.start()
    assert fast.ready.wait(SAFETY)
    slow = _slow_socket(server, b"GET /api/events HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n")
    wait_for(lambda: feed.clients == 2, what="the slow client to subscribe")
    published = _publish_keeping_pace(feed, fast)

    body = _read_all(slow)  # now it reads: what was buffered, then the notice, then the end
    slow.close()
    # The fast client is still subscribed (it is stopped only after this), so one remains.
    wait_for(lambda: feed.clients == 1, what="the slow client to be dropped")
    fast.stop.set()
    messages = [json.loads(line[6:]) for line in body.split(b"\n") if line.startswith(b"data: ")]
    steps = [m["seq"] for m in messages if m["kind"] == "step"]
    assert messages[-1]["kind"] == "lagged" and "reconnect" in messages[-1]["detail"]
    assert 0 < len(steps) < EVENTS  # it got a prefix before it fell behind ...
    assert steps == published[: len(steps)]  # ... in order, none skipped
    # The fast client lost nothing (state ticks are interleaved; numbers are contiguous).
    assert [s for s in fast.seqs if s in set(published)] == published
    assert fast.seqs == list(range(fast.seqs[0], fast.seqs[-1] + 1))
    assert "lagged" not in fast.kinds


def _ws_frames(data: bytes) -> list[tuple[int, bytes]]:
    """(opcode, payload) of each complete server frame (unmasked, unfragmented) in `data`."""
    frames, at = [], 0
    while at + 2 <= len(data):
        opcode, size, head = data[at] & 0x0F, data[at + 1] & 0x7F, 2
        if size == 126:
            size, head = int.from_bytes(data[at + 2 : at + 4], "big"), 4
        elif size == 127:
            size, head = int.from_bytes(data[at + 2 : at + 10], "big"), 10
        if at + head + size > len(data):
            break
        frames.append((opcode, data[at + head : at + head + size]))
        at += head + size
    return frames


def test_a_slow_websocket_client_is_told_and_closed_while_a_fast_one_gets_everything(
    serve: Serve,
) -> None:
    server = serve(make_agent())
    feed = server.app.state.web.feed
    fast = FastReader(server.url)
    fast.start()
    assert fast.ready.wait(SAFETY)
    key = base64.b64encode(os.urandom(16))
    slow = _slow_socket(
        server,
        b"GET /ws/status HTTP/1.1\r\nHost: 127.0.0.1\r\n"
        b"Upgrade: websocket\r\nConnection: Upgrade\r\n"
        b"Sec-WebSocket-Key: " + key + b"\r\n"
        b"Sec-WebSocket-Version: 13\r\n\r\n",
    )
    wait_for(lambda: feed.clients == 2, what="the WebSocket client to subscribe")
    published = _publish_keeping_pace(feed, fast)
    fast.stop.set()

    slow.settimeout(SAFETY)
    data, deadline = b"", time.monotonic() + 60
    while not any(op == 8 for op, _ in _ws_frames(data.partition(b"\r\n\r\n")[2])):
        assert time.monotonic() < deadline, "the server did not close the WebSocket"
        chunk = slow.recv(1 << 16)
        assert chunk, "the connection ended without a close frame"
        data += chunk
    slow.close()
    frames = _ws_frames(data.partition(b"\r\n\r\n")[2])
    messages = [json.loads(payload) for op, payload in frames if op == 1]
    close = next(payload for op, payload in frames if op == 8)
    assert int.from_bytes(close[:2], "big") == 1013 and b"lagged" in close[2:]
    assert messages[-1]["kind"] == "lagged"
    steps = [m["seq"] for m in messages if m["kind"] == "step"]
    assert 0 < len(steps) < EVENTS and steps == published[: len(steps)]
    assert [s for s in fast.seqs if s in set(published)] == published
