"""Camera frames for vision models: a downscaled JPEG as a data URL (Pillow, the `llm` extra)."""

from __future__ import annotations

import base64

from ..camera import encode_jpeg
from ..state import CameraFrame


def jpeg_data_url(frame: CameraFrame, max_side: int = 512, quality: int = 80) -> str:
    """`data:image/jpeg;base64,...` of the frame, longest side at most `max_side` pixels.

    Raises ValueError when the frame cannot be converted or Pillow is missing.
    """
    try:
        data = encode_jpeg(frame, max_side, quality)
    except ImportError as exc:
        raise ValueError("vision needs Pillow: pip install 'shadowhound[llm]'") from exc
    return "data:image/jpeg;base64," + base64.b64encode(data).decode("ascii")
