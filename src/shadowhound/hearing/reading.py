"""Reading recordings in worker processes of their own.

Reading a length walks a container in Python (bounded: a few milliseconds for what a browser
sends, some tens for a crafted Ogg of 1,500 pages). In a thread of the server that work holds
the interpreter's lock, which the event loop needs to answer the e-stop, and on a busy machine a
thread preempted while holding it holds the loop for as long as the scheduler likes. In a
process of its own it holds nothing of the server's: the lane thread that waits for it has let
go of the lock.

A reader is `python -m shadowhound.hearing.reading`, a plain child process (not
multiprocessing, which would import the server's own main script again), fed over its stdin:
a frame of (header length, body length), a JSON header (`type`, `max_seconds`) and the
recording; it answers one length-prefixed JSON object. It ends when its stdin closes, so it
ends with the server however the server ended. `READERS` are the server process's, shared by
its apps and started with the first app that hears (`warm`), not by the first recording.
"""

from __future__ import annotations

import json
import os
import queue
import select
import struct
import subprocess
import sys
import threading
from pathlib import Path
from typing import IO, Any

from ..errors import AudioProblem, HearingBusy, RecordingTooLong, RecordingUnreadable
from .audio import Audio, inspect

PROCESSES = 2  # one for each reading lane (the general and the urgent one)
ANSWER_SECONDS = 10.0  # a reader that has not answered by then is ended (reading takes ms)
_FRAME = struct.Struct(">II")
_SIZE = struct.Struct(">I")
_PACKAGE_ROOT = str(Path(__file__).resolve().parents[2])  # the directory holding shadowhound/


class Reader:
    """One reader process, started on demand, one recording at a time."""

    def __init__(self) -> None:
        self._process: subprocess.Popen[bytes] | None = None

    @property
    def pid(self) -> int | None:
        """The process's id while it runs."""
        return self._process.pid if self._process is not None else None

    def start(self) -> None:
        if self._process is not None and self._process.poll() is None:
            return
        env = dict(os.environ)
        env["PYTHONPATH"] = os.pathsep.join(
            p for p in (_PACKAGE_ROOT, env.get("PYTHONPATH", "")) if p
        )
        self._process = subprocess.Popen(
            [sys.executable, "-m", "shadowhound.hearing.reading"],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            env=env,
        )

    def inspect(self, data: bytes, content_type: str, max_seconds: float) -> Audio:
        self.start()
        process = self._process
        assert process is not None and process.stdin is not None and process.stdout is not None
        header = json.dumps({"type": content_type, "max_seconds": max_seconds}).encode()
        try:
            process.stdin.write(_FRAME.pack(len(header), len(data)) + header + data)
            process.stdin.flush()
            size = _SIZE.unpack(_read(process.stdout, _SIZE.size))[0]
            answer = json.loads(_read(process.stdout, size))
        except (OSError, ValueError, struct.error):
            self.stop()  # died, or answered nonsense: a new one next time
            raise HearingBusy("the recording's reader stopped: say it again", 503) from None
        return _answered(answer)

    def stop(self) -> None:
        process, self._process = self._process, None
        if process is not None:
            process.kill()
            process.wait()


class Readers:
    """`PROCESSES` readers; a caller waits for a free one (there is one for each lane)."""

    def __init__(self, processes: int = PROCESSES) -> None:
        self._free: queue.Queue[Reader] = queue.Queue()
        for _ in range(processes):
            self._free.put(Reader())
        self._all = list(self._free.queue)
        self._lock = threading.Lock()

    def warm(self) -> None:
        """Start the processes now (returns at once), so that no recording waits for them."""
        with self._lock:
            for reader in self._all:
                reader.start()

    def inspect(self, data: bytes, content_type: str, max_seconds: float) -> Audio:
        """`hearing.inspect` in a reader process (the caller's thread waits, holding nothing)."""
        reader = self._free.get()
        try:
            return reader.inspect(data, content_type, max_seconds)
        finally:
            self._free.put(reader)

    def close(self) -> None:
        with self._lock:
            for reader in self._all:
                reader.stop()


def _read(stream: IO[bytes], size: int) -> bytes:
    chunks, left = [], size
    while left:
        ready, _, _ = select.select([stream], [], [], ANSWER_SECONDS)
        chunk = os.read(stream.fileno(), left) if ready else b""
        if not chunk:
            raise OSError("the reader ended or did not answer")
        chunks.append(chunk)
        left -= len(chunk)
    return b"".join(chunks)


def _answered(answer: dict[str, Any]) -> Audio:
    if "audio" in answer:
        return Audio(**answer["audio"])
    if "too_long" in answer:
        seconds, limit, exact = answer["too_long"]
        raise RecordingTooLong(seconds, limit, exact=exact)
    problem = RecordingUnreadable if answer.get("unreadable") else AudioProblem
    raise problem(answer["problem"])


def _answer(data: bytes, header: dict[str, Any]) -> dict[str, Any]:
    try:
        audio = inspect(data, header["type"], header["max_seconds"])
    except RecordingTooLong as exc:
        return {"too_long": [exc.seconds, exc.limit, exc.exact]}
    except AudioProblem as exc:
        return {"problem": str(exc), "unreadable": isinstance(exc, RecordingUnreadable)}
    return {
        "audio": {"kind": audio.kind, "seconds": audio.seconds, "content_type": audio.content_type}
    }


def main() -> None:
    """A reader: frames in on stdin, answers out on stdout, until stdin closes."""
    source, sink = sys.stdin.buffer, sys.stdout.buffer
    while True:
        frame = source.read(_FRAME.size)
        if len(frame) < _FRAME.size:
            return  # the server has gone
        header_size, body_size = _FRAME.unpack(frame)
        header = json.loads(source.read(header_size))
        raw = json.dumps(_answer(source.read(body_size), header)).encode()
        sink.write(_SIZE.pack(len(raw)) + raw)
        sink.flush()


READERS = Readers()  # the server process's readers, shared by its apps; they end with it

if __name__ == "__main__":
    main()
