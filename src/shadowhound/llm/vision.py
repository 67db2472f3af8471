"""Camera frames for vision models: downscaled JPEG as a data URL (needs Pillow, `llm` extra)."""

from __future__ import annotations

import base64
import io

from ..state import CameraFrame

_RAW_MODES = {"rgb8": "RGB", "bgr8": "RGB", "mono8": "L"}


def jpeg_data_url(frame: CameraFrame, max_side: int = 512, quality: int = 80) -> str:
    """`data:image/jpeg;base64,...` of the frame, longest side at most `max_side` pixels."""
    try:
        from PIL import Image
    except ImportError as exc:
        raise ValueError("vision needs Pillow: pip install 'shadowhound[llm]'") from exc
    image: Image.Image
    if frame.encoding in ("jpeg", "png"):
        image = Image.open(io.BytesIO(frame.data))
        image.load()
    elif frame.encoding in _RAW_MODES:
        image = Image.frombytes(_RAW_MODES[frame.encoding], (frame.width, frame.height),
                                frame.data)
        if frame.encoding == "bgr8":
            b, g, r = image.split()
            image = Image.merge("RGB", (r, g, b))
    else:
        raise ValueError(f"unsupported frame encoding {frame.encoding!r}")
    image = image.convert("RGB")
    image.thumbnail((max_side, max_side))
    out = io.BytesIO()
    image.save(out, format="JPEG", quality=quality)
    return "data:image/jpeg;base64," + base64.b64encode(out.getvalue()).decode("ascii")
