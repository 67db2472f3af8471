"""A scripted OpenAI-compatible chat-completions server for tests (loopback only).

Start it, queue replies, point any OpenAI client at ``srv.url``::

    with ScriptedLLM() as srv:
        srv.script(text("hello"), tool_calls(("move", {"x": 1.0})), status(500))
        client = OpenAI(base_url=srv.url, api_key="test", max_retries=0, timeout=5)
        ...
        assert srv.requests[0]["messages"][0]["role"] == "system"

Every ``POST /v1/chat/completions`` takes the next reply from a FIFO queue. An empty queue
answers HTTP 500 ``{"error": {"message": "no scripted reply left", "type": "server_error"}}``.
Also served: ``GET /v1/models``, ``GET /v1/models/{id}`` and, when ``ollama_tags`` is given,
the Ollama-native ``GET /api/tags``. Everything else is a 404 with a JSON error body.

``holding()`` says how many requests a ``hang()`` or ``delay()`` reply holds unanswered right
now, so a test can say "the client gave up (or the mission ended) while the server still held
its request" without measuring time; ``release()`` lets go of them (each connection is dropped)
while the server serves on.
"""

from __future__ import annotations

import contextlib
import json
import socket
import sys
import threading
import time
from collections import deque
from collections.abc import Callable, Iterable, Iterator
from dataclasses import dataclass, field
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any

__all__ = [
    "Reply",
    "ScriptedLLM",
    "delay",
    "drop",
    "dynamic",
    "garbage",
    "hang",
    "json_plan",
    "status",
    "text",
    "tool_calls",
]

NO_REPLY_LEFT = "no scripted reply left"
_POLL_INTERVAL = 0.05  # serve_forever poll interval: bounds how long stop() waits


# --------------------------------------------------------------------------- replies


@dataclass(frozen=True)
class Reply:
    """One scripted answer. Build it with the module-level constructors, not directly.

    ``kind`` is one of ``"message"``, ``"status"``, ``"delay"``, ``"hang"``, ``"drop"``,
    ``"raw"``, ``"dynamic"``; the other fields are used by the kinds that need them.
    """

    kind: str
    content: str | None = None
    calls: tuple[tuple[str, str], ...] = ()  # (name, arguments JSON text)
    finish_reason: str = "stop"
    usage: tuple[int, int] | None = None
    status: int = 200
    message: str = ""
    headers: tuple[tuple[str, str], ...] = ()
    body: bytes = b""
    content_type: str = "application/json"
    seconds: float = 0.0
    then: Reply | None = None
    fn: Callable[[dict[str, Any]], Reply] | None = field(default=None, compare=False)


def model_settings(srv: Any, **llm: Any) -> dict[str, Any]:
    """The `llm` section for an agent whose every mission this scripted server plans: no
    retries, hybrid planning off (the offline planner would answer first). The time-out only
    bounds a hung test (a loaded machine may take seconds to answer on loopback); a test of
    the time-out sets its own."""
    return {
        "base_url": srv.url,
        "model": "test-model",
        "max_retries": 0,
        "timeout": 60,
        "hybrid": False,
        **llm,
    }


def text(content: str, *, usage: tuple[int, int] | None = (50, 10)) -> Reply:
    """A normal assistant message. ``usage=None`` omits the ``usage`` field entirely."""
    return Reply(kind="message", content=content, usage=usage)


def tool_calls(
    *calls: tuple[str, dict[str, Any] | str],
    content: str | None = None,
    usage: tuple[int, int] | None = (50, 10),
) -> Reply:
    """An assistant message with ``tool_calls`` and ``finish_reason="tool_calls"``.

    Each call is ``(name, arguments)``: a dict is sent as ``json.dumps(arguments)``, a string
    verbatim (so malformed arguments can be scripted). Call ids are ``call_1``, ``call_2``, ...
    numbered across the whole server run, in the order they are served.
    """
    encoded = tuple(
        (name, args if isinstance(args, str) else json.dumps(args)) for name, args in calls
    )
    return Reply(
        kind="message", content=content, calls=encoded, finish_reason="tool_calls", usage=usage
    )


def json_plan(steps: list[dict[str, Any]], **kw: Any) -> Reply:
    """``text(json.dumps({"steps": steps}), **kw)``."""
    return text(json.dumps({"steps": steps}), **kw)


def status(code: int, message: str = "boom", *, retry_after_ms: int | None = None) -> Reply:
    """HTTP ``code`` with an OpenAI-style error body.

    ``retry_after_ms`` (> 0) adds a ``retry-after-ms`` header, which the openai client honours
    instead of its own backoff (about 0.5 s before the first retry): keeps retry tests fast.
    """
    headers = () if retry_after_ms is None else (("retry-after-ms", str(retry_after_ms)),)
    return Reply(kind="status", status=code, message=message, headers=headers)


def delay(seconds: float, then: Reply) -> Reply:
    """Wait ``seconds`` (cut short by ``stop()`` or ``release()``, then the connection is
    dropped), send ``then``."""
    return Reply(kind="delay", seconds=seconds, then=then)


def hang() -> Reply:
    """Read the request and never answer: a model server that is stuck. ``stop()``,
    ``release()`` or the client hanging up ends it; ``hung_up()`` tells whether the client
    closed the connection."""
    return Reply(kind="hang")


def drop() -> Reply:
    """Read the request, then close the connection without sending any response."""
    return Reply(kind="drop")


def garbage(body: bytes, status: int = 200, content_type: str = "application/json") -> Reply:
    """Send ``body`` verbatim (malformed JSON, HTML error pages, ...)."""
    return Reply(kind="raw", body=body, status=status, content_type=content_type)


def dynamic(fn: Callable[[dict[str, Any]], Reply]) -> Reply:
    """Compute the reply from the request body. If ``fn`` raises, the client gets a 500."""
    return Reply(kind="dynamic", fn=fn)


def _error_body(message: str, code: int) -> dict[str, Any]:
    kind = "server_error" if code >= 500 else "invalid_request_error"
    return {"error": {"message": message, "type": kind, "param": None, "code": None}}


# --------------------------------------------------------------------------- HTTP plumbing


class _Server(ThreadingHTTPServer):
    daemon_threads = True
    allow_reuse_address = True
    owner: ScriptedLLM

    def handle_error(self, request: Any, client_address: Any) -> None:
        # Clients that time out or hang up are routine here; anything else is a helper bug.
        exc = sys.exc_info()[1]
        if isinstance(exc, OSError):
            return
        super().handle_error(request, client_address)


class _Handler(BaseHTTPRequestHandler):
    protocol_version = "HTTP/1.1"
    disable_nagle_algorithm = True  # else headers and body writes meet delayed ACKs: ~40 ms/request
    server_version = "ScriptedLLM/1.0"
    sys_version = ""
    server: _Server

    # -- lifecycle: track open connections so stop() can unblock keep-alive readers

    def setup(self) -> None:
        super().setup()
        self.server.owner._track(self.connection, add=True)

    def finish(self) -> None:
        try:
            super().finish()
        finally:
            self.server.owner._track(self.connection, add=False)

    def log_message(self, format: str, *args: Any) -> None:  # noqa: A002 - base signature
        pass

    # -- routing

    def do_GET(self) -> None:  # noqa: N802 - http.server naming
        owner = self.server.owner
        path = self.path.split("?", 1)[0].rstrip("/")
        if path == "/v1/models":
            data = [{"id": m, "object": "model", "owned_by": "test"} for m in owner.models]
            self._send_json(200, {"object": "list", "data": data})
        elif path.startswith("/v1/models/") and path[len("/v1/models/") :] in owner.models:
            model = path[len("/v1/models/") :]
            self._send_json(200, {"id": model, "object": "model", "owned_by": "test"})
        elif path == "/api/tags" and owner.ollama_tags is not None:
            models = [{"name": n, "model": n} for n in owner.ollama_tags]
            self._send_json(200, {"models": models})
        else:
            self._not_found()

    def do_POST(self) -> None:  # noqa: N802 - http.server naming
        raw = self._read_body()
        if raw is None:
            return
        path = self.path.split("?", 1)[0].rstrip("/")
        if path != "/v1/chat/completions":
            self._not_found()
            return
        try:
            body = json.loads(raw)
        except (UnicodeDecodeError, ValueError) as exc:
            self._send_error(400, f"request body is not valid JSON: {exc}")
            return
        if not isinstance(body, dict):
            self._send_error(400, "request body must be a JSON object")
            return
        owner = self.server.owner
        owner._record(body)
        if body.get("stream"):
            self._send_error(400, "ScriptedLLM does not script streaming; send stream=false")
            return
        reply = owner._next_reply()
        if reply is None:
            self._send_error(500, NO_REPLY_LEFT)
            return
        self._serve(reply, body)

    def do_PUT(self) -> None:  # noqa: N802
        if self._read_body() is not None:
            self._not_found()

    do_DELETE = do_PATCH = do_PUT  # noqa: N815
    do_HEAD = do_GET  # noqa: N815 - a HEAD body is never read by well-behaved clients

    # -- replies

    def _serve(self, reply: Reply, body: dict[str, Any]) -> None:
        owner = self.server.owner
        if reply.kind == "message":
            self._send_json(200, owner._completion(reply, body))
        elif reply.kind == "status":
            headers = dict(reply.headers)
            self._send_json(reply.status, _error_body(reply.message, reply.status), headers)
        elif reply.kind == "raw":
            self._send_bytes(reply.status, reply.body, reply.content_type)
        elif reply.kind == "drop":
            self._drop()
        elif reply.kind == "hang":
            with owner._holding():
                hung_up = self._hang()
            if hung_up:  # counted once no longer held: a test that sees it sees both
                owner._note_hangup()
            self._drop()
        elif reply.kind == "delay":
            with owner._holding() as let_go:
                waited_out = not let_go(reply.seconds)
            if waited_out and reply.then is not None:
                self._serve(reply.then, body)
            else:
                self._drop()  # stopping or released: never hold stop() up
        elif reply.kind == "dynamic" and reply.fn is not None:
            try:
                produced = reply.fn(body)
            except Exception as exc:  # surfaced to the client, not swallowed
                self._send_error(500, f"dynamic reply raised {type(exc).__name__}: {exc}")
                return
            if not isinstance(produced, Reply):
                self._send_error(500, f"dynamic reply returned {type(produced).__name__}")
                return
            self._serve(produced, body)
        else:
            self._send_error(500, f"unknown scripted reply kind {reply.kind!r}")

    def _hang(self) -> bool:
        """Wait, answering nothing, until the server stops or lets go (False), or the client
        closes the connection (True)."""
        let_go = self.server.owner._let_go_marker()
        self.connection.settimeout(_POLL_INTERVAL)
        while not let_go():
            try:
                if self.connection.recv(1, socket.MSG_PEEK) == b"":
                    return True
            except TimeoutError:
                continue
            except OSError:
                return True
        return False

    def _drop(self) -> None:
        self.close_connection = True
        with contextlib.suppress(OSError):
            self.connection.shutdown(socket.SHUT_RDWR)
        self.connection.close()

    def _read_body(self) -> bytes | None:
        """The request body (Content-Length or chunked); None after answering a bad request."""
        if "chunked" in self.headers.get("Transfer-Encoding", "").lower():
            chunks: list[bytes] = []
            while True:
                size = int(self.rfile.readline().split(b";", 1)[0].strip() or b"0", 16)
                if size == 0:
                    while self.rfile.readline() not in (b"\r\n", b"\n", b""):
                        pass  # trailers
                    return b"".join(chunks)
                chunks.append(self.rfile.read(size))
                self.rfile.readline()
        try:
            length = int(self.headers.get("Content-Length", "0"))
        except ValueError:
            self.close_connection = True
            self._send_error(400, "bad Content-Length")
            return None
        return self.rfile.read(length) if length > 0 else b""

    def _not_found(self) -> None:
        self._send_error(404, f"no route for {self.command} {self.path}")

    def _send_error(self, code: int, message: str) -> None:
        self._send_json(code, _error_body(message, code))

    def _send_json(
        self, code: int, payload: dict[str, Any], headers: dict[str, str] | None = None
    ) -> None:
        self._send_bytes(code, json.dumps(payload).encode(), "application/json", headers)

    def _send_bytes(
        self,
        code: int,
        data: bytes,
        content_type: str,
        headers: dict[str, str] | None = None,
    ) -> None:
        try:
            self.send_response(code)
            self.send_header("Content-Type", content_type)
            self.send_header("Content-Length", str(len(data)))
            for name, value in (headers or {}).items():
                self.send_header(name, value)
            self.end_headers()
            if self.command != "HEAD":
                self.wfile.write(data)
        except OSError:  # the client gave up (timeout) or hung up
            self.close_connection = True


# --------------------------------------------------------------------------- the server


class ScriptedLLM:
    """An OpenAI-compatible chat-completions server on 127.0.0.1 answering from a script."""

    def __init__(
        self, models: Iterable[str] = ("test-model",), *, ollama_tags: list[str] | None = None
    ) -> None:
        self.models: tuple[str, ...] = tuple(models)
        self.ollama_tags: list[str] | None = None if ollama_tags is None else list(ollama_tags)
        self.requests: list[dict[str, Any]] = []
        self._queue: deque[Reply] = deque()
        self._lock = threading.Lock()
        self._stopping = threading.Event()
        self._connections: set[socket.socket] = set()
        self._server: _Server | None = None
        self._thread: threading.Thread | None = None
        self._completion_ids = 0
        self._call_ids = 0
        self._hangups = 0
        self._held = 0  # requests a hang() or delay() holds unanswered now
        self._releases = 0  # release() calls so far: a hold started before one is let go

    # -- addresses

    @property
    def port(self) -> int:
        if self._server is None:
            raise RuntimeError("ScriptedLLM is not running; call start() or use it as a context")
        return int(self._server.server_address[1])

    @property
    def root(self) -> str:
        """``http://127.0.0.1:PORT``"""
        return f"http://127.0.0.1:{self.port}"

    @property
    def url(self) -> str:
        """``http://127.0.0.1:PORT/v1``: the OpenAI ``base_url``."""
        return f"{self.root}/v1"

    # -- lifecycle

    def start(self) -> ScriptedLLM:
        if self._server is not None:
            raise RuntimeError("ScriptedLLM is already running")
        self._stopping.clear()
        server = _Server(("127.0.0.1", 0), _Handler)
        server.owner = self
        self._server = server
        self._thread = threading.Thread(
            target=server.serve_forever,
            kwargs={"poll_interval": _POLL_INTERVAL},
            name=f"ScriptedLLM:{self.port}",
            daemon=True,
        )
        self._thread.start()
        return self

    def stop(self) -> None:
        """Stop serving; wakes pending delay() replies and closes keep-alive connections."""
        server, thread = self._server, self._thread
        if server is None:
            return
        self._stopping.set()
        server.shutdown()
        server.server_close()
        with self._lock:
            connections = list(self._connections)
        for conn in connections:
            with contextlib.suppress(OSError):
                conn.shutdown(socket.SHUT_RDWR)
        if thread is not None:
            thread.join(timeout=2)
        self._server = self._thread = None

    def __enter__(self) -> ScriptedLLM:
        return self.start()

    def __exit__(self, *exc: object) -> None:
        self.stop()

    # -- script

    def script(self, *replies: Reply) -> None:
        """Append replies to the FIFO queue."""
        for reply in replies:
            if not isinstance(reply, Reply):
                raise TypeError(f"script() takes Reply objects, got {type(reply).__name__}")
        with self._lock:
            self._queue.extend(replies)

    def pending(self) -> int:
        """How many scripted replies are left."""
        with self._lock:
            return len(self._queue)

    def clear(self) -> None:
        """Drop the scripted replies still queued (recorded requests are kept)."""
        with self._lock:
            self._queue.clear()

    def hung_up(self) -> int:
        """How many clients closed their connection while a ``hang()`` reply held it."""
        with self._lock:
            return self._hangups

    def holding(self) -> int:
        """How many requests a ``hang()`` or ``delay()`` reply holds unanswered right now."""
        with self._lock:
            return self._held

    def release(self) -> None:
        """Let go of every request held now: each connection is dropped (the client sees a lost
        connection), as ``stop()`` does, but the server serves on; later holds are held."""
        with self._lock:
            self._releases += 1

    # -- used by the handler threads

    @contextlib.contextmanager
    def _holding(self) -> Iterator[Callable[[float], bool]]:
        """Count a held request while inside; yields `wait(seconds)`, True when let go first."""
        let_go = self._let_go_marker()

        def wait(seconds: float) -> bool:
            end = time.monotonic() + seconds
            while not let_go():
                left = end - time.monotonic()
                if left <= 0:
                    return False
                self._stopping.wait(min(left, _POLL_INTERVAL))
            return True

        with self._lock:
            self._held += 1
        try:
            yield wait
        finally:
            with self._lock:
                self._held -= 1

    def _let_go_marker(self) -> Callable[[], bool]:
        """A check, true once the server stops or release() is called after this call."""
        with self._lock:
            releases = self._releases

        def let_go() -> bool:
            with self._lock:
                return self._stopping.is_set() or self._releases != releases

        return let_go

    def _note_hangup(self) -> None:
        with self._lock:
            self._hangups += 1

    def _next_reply(self) -> Reply | None:
        with self._lock:
            return self._queue.popleft() if self._queue else None

    def _record(self, body: dict[str, Any]) -> None:
        with self._lock:
            self.requests.append(body)

    def _track(self, conn: socket.socket, *, add: bool) -> None:
        with self._lock:
            if add:
                self._connections.add(conn)
            else:
                self._connections.discard(conn)

    def _completion(self, reply: Reply, body: dict[str, Any]) -> dict[str, Any]:
        with self._lock:
            self._completion_ids += 1
            completion_id = f"chatcmpl-{self._completion_ids}"
            call_ids = range(self._call_ids + 1, self._call_ids + 1 + len(reply.calls))
            self._call_ids += len(reply.calls)
        message: dict[str, Any] = {"role": "assistant", "content": reply.content}
        if reply.calls:
            message["tool_calls"] = [
                {
                    "id": f"call_{n}",
                    "type": "function",
                    "function": {"name": name, "arguments": arguments},
                }
                for n, (name, arguments) in zip(call_ids, reply.calls, strict=True)
            ]
        result: dict[str, Any] = {
            "id": completion_id,
            "object": "chat.completion",
            "created": int(time.time()),
            "model": body.get("model") or (self.models[0] if self.models else "test-model"),
            "choices": [{"index": 0, "message": message, "finish_reason": reply.finish_reason}],
        }
        if reply.usage is not None:
            prompt, completion = reply.usage
            result["usage"] = {
                "prompt_tokens": prompt,
                "completion_tokens": completion,
                "total_tokens": prompt + completion,
            }
        return result
