"""A minimal MCP client over raw sockets, for tests and benchmarks that must drop a connection
at a moment of their choosing: each request is one HTTP/1.1 request on its own connection.

Any protocol version: the handshake era (2024-11-05 to 2025-11-25) opens a session with
`initialize`; 2026-07-28 sends every request with its own envelope and no session.
"""

from __future__ import annotations

import json
import re
import socket
import time
from dataclasses import dataclass, field
from typing import Any

MODERN = "2026-07-28"
HANDSHAKE_VERSIONS = ["2024-11-05", "2025-03-26", "2025-06-18", "2025-11-25"]
ALL_VERSIONS = [*HANDSHAKE_VERSIONS, MODERN]


@dataclass
class Answer:
    """A whole HTTP answer: status, headers (lower-case names) and the JSON-RPC messages in its
    body (one JSON object, or Server-Sent Events)."""

    status: int
    headers: dict[str, str]
    messages: list[dict[str, Any]] = field(default_factory=list)

    def result(self) -> dict[str, Any]:
        for message in self.messages:
            if "result" in message:
                return dict(message["result"])
        raise AssertionError(f"no result in the answer: {self.status} {self.messages}")


class Stream:
    """A request whose answer is still coming: read it as it arrives, or drop the connection."""

    def __init__(self, sock: socket.socket) -> None:
        self.sock = sock
        self.received = b""

    def wait_for(self, text: bytes, timeout: float = 60.0) -> None:
        """Until `text` has arrived on the stream."""
        deadline = time.monotonic() + timeout
        while text not in self.received:
            left = deadline - time.monotonic()
            if left <= 0:
                raise AssertionError(f"{text!r} never arrived; got {self.received[-500:]!r}")
            self.sock.settimeout(left)
            chunk = self.sock.recv(65536)
            if not chunk:
                raise AssertionError(f"closed before {text!r}; got {self.received[-500:]!r}")
            self.received += chunk

    def close(self) -> None:
        """Drop the connection, as a client that goes away does."""
        self.sock.close()


class Caller:
    """JSON-RPC requests of one protocol `version` (numbered from 1), for any transport."""

    def __init__(self, version: str) -> None:
        self.version = version
        self._ids = 0

    @property
    def modern(self) -> bool:
        return self.version == MODERN

    def initialize_body(self) -> dict[str, Any]:
        return self.request_body(
            "initialize",
            {
                "protocolVersion": self.version,
                "capabilities": {},
                "clientInfo": {"name": "wire", "version": "0"},
            },
        )

    def request_body(self, method: str, params: dict[str, Any] | None = None) -> dict[str, Any]:
        self._ids += 1
        params = dict(params or {})
        if self.modern:
            meta = dict(params.get("_meta", {}))
            meta["io.modelcontextprotocol/protocolVersion"] = MODERN
            meta["io.modelcontextprotocol/clientCapabilities"] = {}
            meta["io.modelcontextprotocol/clientInfo"] = {"name": "wire", "version": "0"}
            params["_meta"] = meta
        return {"jsonrpc": "2.0", "id": self._ids, "method": method, "params": params}

    def tool_call(
        self, name: str, arguments: dict[str, Any], progress: bool = False
    ) -> dict[str, Any]:
        params: dict[str, Any] = {"name": name, "arguments": arguments}
        if progress:
            params["_meta"] = {"progressToken": f"p{self._ids + 1}"}
        return self.request_body("tools/call", params)


class Wire(Caller):
    """Requests to the MCP endpoint at `url`, in protocol `version`, over HTTP."""

    def __init__(self, url: str, version: str) -> None:
        super().__init__(version)
        match = re.match(r"http://([^/:]+|\[[^\]]+\]):(\d+)(/\S*)", url)
        assert match, url
        self.host, self.port, self.path = match.group(1).strip("[]"), int(match.group(2)), match[3]
        self.session: str | None = None

    def initialize(self) -> str | None:
        """Open a session (handshake era); the session id, or None on 2026-07-28."""
        if self.modern:
            return None
        answer = self.send(self.initialize_body())
        assert answer.status == 200, answer
        self.session = answer.headers["mcp-session-id"]
        self.send({"jsonrpc": "2.0", "method": "notifications/initialized"})
        return self.session

    def send(self, body: dict[str, Any], method: str = "POST") -> Answer:
        """One request, its whole answer."""
        sock = self._connect(method, body)
        data = b""
        while chunk := sock.recv(65536):
            data += chunk
        sock.close()
        return _parse(data)

    def open(self, body: dict[str, Any]) -> Stream:
        """Send a request and leave its answer coming."""
        return Stream(self._connect("POST", body))

    def open_get_stream(self) -> Stream:
        """The session's GET stream (server-to-client messages); open until dropped."""
        stream = Stream(self._connect("GET", None))
        stream.wait_for(b"\r\n\r\n")
        return stream

    def delete(self) -> Answer:
        return self.send({}, method="DELETE")

    def call(self, name: str, arguments: dict[str, Any] | None = None) -> dict[str, Any]:
        """A tool call's result (structured content when there is some)."""
        result = self.send(self.tool_call(name, arguments or {})).result()
        return dict(result.get("structuredContent") or result)

    def _connect(self, method: str, body: dict[str, Any] | None) -> socket.socket:
        data = json.dumps(body).encode() if body is not None and method == "POST" else b""
        headers = {
            "Host": f"{self.host}:{self.port}",
            "Accept": "application/json, text/event-stream",
            "Connection": "close",
        }
        if method == "POST":
            headers["Content-Type"] = "application/json"
            headers["Content-Length"] = str(len(data))
        if self.session:
            headers["Mcp-Session-Id"] = self.session
        if body and body.get("method") != "initialize" and (self.modern or self.session):
            headers["MCP-Protocol-Version"] = self.version
        if self.modern and body and "method" in body:
            headers["Mcp-Method"] = body["method"]
            name = (body.get("params") or {}).get("name")
            if name is not None:
                headers["Mcp-Name"] = name
        head = f"{method} {self.path} HTTP/1.1\r\n" + "".join(
            f"{k}: {v}\r\n" for k, v in headers.items()
        )
        sock = socket.create_connection((self.host, self.port), timeout=60)
        sock.sendall(head.encode() + b"\r\n" + data)
        return sock


def _parse(data: bytes) -> Answer:
    head, _, body = data.partition(b"\r\n\r\n")
    lines = head.decode("latin-1").split("\r\n")
    status = int(lines[0].split()[1])
    headers = {}
    for line in lines[1:]:
        name, _, value = line.partition(":")
        headers[name.strip().lower()] = value.strip()
    if headers.get("transfer-encoding") == "chunked":
        body = _dechunk(body)
    text = body.decode()
    messages: list[dict[str, Any]] = []
    if headers.get("content-type", "").startswith("text/event-stream"):
        for line in text.splitlines():
            if line.startswith("data:") and line[5:].strip():
                messages.append(json.loads(line[5:]))
    elif text.strip():
        messages.append(json.loads(text))
    return Answer(status, headers, messages)


def _dechunk(body: bytes) -> bytes:
    out = b""
    while body:
        size_line, _, rest = body.partition(b"\r\n")
        size = int(size_line.split(b";")[0], 16)
        if size == 0:
            break
        out += rest[:size]
        body = rest[size + 2 :]
    return out
