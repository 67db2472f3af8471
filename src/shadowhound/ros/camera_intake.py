"""Camera frames off the executor: the callback only keeps the newest message; a thread of its
own converts it and hands it to the agent.

At 30 frames/s, converting each frame in the executor's callback (a raw image is copied, a
compressed one is checked) would keep the executor busy and put other callbacks behind it. A
frame that arrives before the previous one was converted replaces it: the agent wants the
newest image, not every image.
"""

from __future__ import annotations

import threading
from collections.abc import Callable
from typing import Any


class CameraIntake:
    """`offer(msg)` from a callback (constant time); `convert(msg)` runs on the intake thread."""

    def __init__(self, convert: Callable[[Any], None]) -> None:
        self._convert = convert
        self._lock = threading.Lock()
        self._newest: Any = None
        self._ready = threading.Event()
        self._closed = False
        self.replaced = 0  # frames replaced by a newer one before they were converted
        self._thread = threading.Thread(target=self._run, name="shadowhound-camera", daemon=True)
        self._thread.start()

    def offer(self, msg: Any) -> None:
        with self._lock:
            if self._newest is not None:
                self.replaced += 1
            self._newest = msg
        self._ready.set()

    def close(self) -> None:
        self._closed = True
        self._ready.set()
        self._thread.join(2.0)

    def _run(self) -> None:
        while True:
            self._ready.wait()
            self._ready.clear()
            if self._closed:
                return
            with self._lock:
                msg, self._newest = self._newest, None
            if msg is not None:
                self._convert(msg)
