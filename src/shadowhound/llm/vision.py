"""Camera frames for vision models: a downscaled JPEG as a data URL (Pillow, the `llm` extra),
and the question about one frame asked of the model."""

from __future__ import annotations

import base64
import threading

from ..camera import encode_jpeg
from ..errors import BackendError
from ..state import CameraFrame
from .backend import LLMBackend


def jpeg_data_url(frame: CameraFrame, max_side: int = 512, quality: int = 80) -> str:
    """`data:image/jpeg;base64,...` of the frame, longest side at most `max_side` pixels.

    Raises ValueError when the frame cannot be converted or Pillow is missing.
    """
    try:
        data = encode_jpeg(frame, max_side, quality)
    except ImportError as exc:
        raise ValueError("vision needs Pillow: pip install 'shadowhound[llm]'") from exc
    return "data:image/jpeg;base64," + base64.b64encode(data).decode("ascii")


def describe_image(
    backend: LLMBackend,
    frame: CameraFrame,
    question: str,
    max_side: int = 512,
    cancelled: threading.Event | None = None,
) -> str:
    """Ask the (vision-capable) model about a downscaled JPEG of the frame.

    Setting `cancelled` abandons the request at once (the caller checks the event)."""
    try:
        url = jpeg_data_url(frame, max_side)
        completion = backend.complete(
            [
                {
                    "role": "user",
                    "content": [
                        {"type": "text", "text": question},
                        {"type": "image_url", "image_url": {"url": url}},
                    ],
                }
            ],
            cancelled=cancelled,
        )
    except (BackendError, ValueError) as exc:
        return f"I could not look at the image: {exc}"
    return str(completion.message.get("content") or "").strip() or "(no answer)"
