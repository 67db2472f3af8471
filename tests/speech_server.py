"""A scripted OpenAI-compatible transcription server for tests (loopback only).

    with ScriptedTranscriber() as srv:
        srv.script("walk forward one meter")        # the next transcripts, in order
        settings.speech.base_url = srv.url           # http://127.0.0.1:PORT/v1
        ...
        assert srv.requests[0].fields["model"] == "whisper-1"

Every `POST /v1/audio/transcriptions` is read as multipart form data as a real server reads it
(the `file` part and the text fields) and answered `{"text": <the next scripted transcript>}`;
the last one is repeated when the queue is empty. `status(code, body)` scripts an error.

A slow server: `hold` picks requests that wait (read, but unanswered) until `release` is set;
`held` counts them (wait on it with `answered`); `delay` gives a request seconds to take.
`answer` picks a transcript per request instead of the script (when requests are answered out
of order).
"""

from __future__ import annotations

import json
import threading
from collections import deque
from collections.abc import Callable
from dataclasses import dataclass, field
from email.parser import BytesParser
from email.policy import HTTP
from http.server import BaseHTTPRequestHandler, ThreadingHTTPServer
from typing import Any


@dataclass
class Heard:
    """One request as the server read it."""

    headers: dict[str, str]
    fields: dict[str, str] = field(default_factory=dict)
    file: bytes = b""
    filename: str = ""
    file_type: str = ""
    at: float = 0.0  # time.monotonic() when answered


@dataclass(frozen=True)
class Status:
    code: int
    body: str


def status(code: int, body: str = "") -> Status:
    return Status(code, body)


class ScriptedTranscriber:
    def __init__(self) -> None:
        self.requests: list[Heard] = []
        self._queue: deque[str | Status] = deque()
        self._last: str | Status = ""
        self._lock = threading.Lock()
        self.answered = threading.Condition(self._lock)
        self.hold: Callable[[Heard], bool] | None = None
        self.answer: Callable[[Heard], str] | None = None
        self.delay: Callable[[Heard], float] | None = None
        self.release = threading.Event()
        self.held = 0
        self._server = ThreadingHTTPServer(("127.0.0.1", 0), self._handler())
        self._server.daemon_threads = True
        self.url = f"http://127.0.0.1:{self._server.server_address[1]}/v1"

    def script(self, *answers: str | Status) -> None:
        with self._lock:
            self._queue.extend(answers)

    def __enter__(self) -> ScriptedTranscriber:
        threading.Thread(target=self._server.serve_forever, args=(0.05,), daemon=True).start()
        return self

    def __exit__(self, *_exc: Any) -> None:
        self.release.set()
        self._server.shutdown()
        self._server.server_close()

    def _next(self) -> str | Status:
        with self._lock:
            if self._queue:
                self._last = self._queue.popleft()
            return self._last

    def _handler(self) -> type[BaseHTTPRequestHandler]:
        server = self

        class Handler(BaseHTTPRequestHandler):
            def log_message(self, *_args: Any) -> None:
                pass

            def do_POST(self) -> None:  # noqa: N802
                import time

                if self.path.rstrip("/") != "/v1/audio/transcriptions":
                    self._send(404, {"error": {"message": f"no route {self.path}"}})
                    return
                length = int(self.headers.get("Content-Length", "0"))
                body = self.rfile.read(length)
                heard = Heard({k.lower(): v for k, v in self.headers.items()})
                head = f"Content-Type: {self.headers.get('Content-Type', '')}\r\n\r\n".encode()
                message = BytesParser(policy=HTTP).parsebytes(head + body)
                for part in message.iter_parts():
                    name = part.get_param("name", header="content-disposition")
                    payload = part.get_payload(decode=True) or b""
                    if name == "file":
                        heard.file, heard.file_type = payload, part.get_content_type()
                        heard.filename = part.get_filename() or ""
                    elif isinstance(name, str):
                        heard.fields[name] = payload.decode()
                if server.hold is not None and server.hold(heard):
                    with server.answered:
                        server.held += 1
                        server.answered.notify_all()
                    server.release.wait()
                if server.delay is not None:
                    time.sleep(server.delay(heard))
                answer = server.answer(heard) if server.answer else server._next()
                with server.answered:
                    heard.at = time.monotonic()
                    server.requests.append(heard)
                    server.answered.notify_all()
                if isinstance(answer, Status):
                    self._send(answer.code, answer.body)
                else:
                    self._send(200, {"text": answer})

            def _send(self, code: int, body: Any) -> None:
                raw = body.encode() if isinstance(body, str) else json.dumps(body).encode()
                self.send_response(code)
                self.send_header("Content-Type", "application/json")
                self.send_header("Content-Length", str(len(raw)))
                self.end_headers()
                self.wfile.write(raw)

        return Handler
