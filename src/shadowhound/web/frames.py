"""Camera frames for the web: JPEG for browsers, shared between clients, encoded at most once.

JPEG frames (a Go2's compressed stream, `update_camera_image(jpeg_bytes)`) pass through
byte-for-byte. PNG (the simulator) and raw frames are converted to JPEG with Pillow when it is
installed; without Pillow a PNG is served as PNG (browsers show PNG parts in an MJPEG stream
too) and a raw frame cannot be shown.
"""

from __future__ import annotations

import logging
import threading
import time
from dataclasses import dataclass
from typing import Any

from ..agent import RobotAgent
from ..camera import encode_jpeg
from ..errors import FrameUnavailable
from ..state import CameraFrame

log = logging.getLogger(__name__)

BOUNDARY = "shadowhound-frame"


@dataclass(frozen=True)
class WebFrame:
    """An image ready to send, and when the camera took it (wall-clock seconds)."""

    data: bytes
    content_type: str
    stamp: float
    width: int
    height: int
    source: str


def to_browser_image(frame: CameraFrame, quality: int = 80) -> tuple[bytes, str]:
    """(bytes, content type): JPEG as is; anything else JPEG-encoded (or PNG without Pillow)."""
    try:
        return encode_jpeg(frame, quality=quality), "image/jpeg"
    except ImportError:
        if frame.encoding == "png":
            return frame.data, "image/png"
        raise FrameUnavailable(
            f"a raw {frame.encoding} frame needs Pillow to be shown "
            "(pip install 'shadowhound[web]')"
        ) from None
    except ValueError as exc:
        raise FrameUnavailable(str(exc)) from exc


class FrameCache:
    """Shares one converted frame between every client; each new frame is converted once."""

    def __init__(self, agent: RobotAgent) -> None:
        self._agent = agent
        self._lock = threading.Lock()
        self._asked = 0.0
        self._frame: CameraFrame | None = None
        self._ready: WebFrame | None = None

    def get(self, max_age: float = 0.0) -> WebFrame:
        """The latest frame for browsers. Raises FrameUnavailable.

        Streams pass `max_age` so several clients asking at once share one request to the
        agent (the simulator renders a new image on every request).
        """
        with self._lock:
            now = time.monotonic()
            if self._ready is not None and now - self._asked < max_age:
                return self._ready
            self._asked = now
            frame = self._agent.latest_frame()
            if frame is None:
                raise FrameUnavailable("no camera frame yet")
            if frame is not self._frame or self._ready is None:
                data, content_type = to_browser_image(frame)
                self._frame = frame
                self._ready = WebFrame(
                    data, content_type, frame.stamp, frame.width, frame.height, frame.source
                )
            return self._ready


def mjpeg_part(frame: WebFrame) -> bytes:
    """One part of a multipart/x-mixed-replace stream."""
    head = (
        f"--{BOUNDARY}\r\nContent-Type: {frame.content_type}\r\n"
        f"Content-Length: {len(frame.data)}\r\nX-Timestamp: {frame.stamp:.6f}\r\n\r\n"
    )
    return head.encode("ascii") + frame.data + b"\r\n"


def frame_summary(frame: WebFrame) -> dict[str, Any]:
    return {
        "content_type": frame.content_type,
        "bytes": len(frame.data),
        "width": frame.width,
        "height": frame.height,
        "stamp": frame.stamp,
        "source": frame.source,
    }
