"""Turning what interfaces and robots receive (bytes, arrays, raw sensor_msgs/Image fields,
frames) into a CameraFrame."""

from __future__ import annotations

import io
import struct
import time
from typing import Any

from .state import CameraFrame

_MAX_BYTES = 50 * 1024 * 1024
RAW_ENCODINGS = {"rgb8": 3, "bgr8": 3, "mono8": 1}
_MAX_RAW_SIDE = 10_000


def image_size(data: bytes) -> tuple[str, int, int]:
    """(encoding, width, height) of JPEG or PNG bytes. Raises ValueError for anything else."""
    if data[:8] == b"\x89PNG\r\n\x1a\n":
        if len(data) < 24 or data[12:16] != b"IHDR":
            raise ValueError("PNG data is truncated (no IHDR header)")
        width, height = struct.unpack(">II", data[16:24])
        return "png", width, height
    if data[:2] == b"\xff\xd8":
        return ("jpeg", *_jpeg_size(data))
    raise ValueError(
        f"image bytes must be JPEG or PNG (unknown signature {data[:4].hex() or 'empty'})"
    )


def _jpeg_size(data: bytes) -> tuple[int, int]:
    i = 2
    while i + 9 < len(data):
        if data[i] != 0xFF:
            raise ValueError("JPEG data is corrupt (bad marker)")
        marker = data[i + 1]
        if marker in (0xD8, 0x01) or 0xD0 <= marker <= 0xD7:
            i += 2
            continue
        (length,) = struct.unpack(">H", data[i + 2 : i + 4])
        if 0xC0 <= marker <= 0xCF and marker not in (0xC4, 0xC8, 0xCC):
            height, width = struct.unpack(">HH", data[i + 5 : i + 9])
            return width, height
        i += 2 + length
    raise ValueError("JPEG data is truncated (no frame header)")


def to_camera_frame(frame: Any, source: str = "camera") -> CameraFrame:
    """Accept a CameraFrame, JPEG/PNG bytes, or an HxWx3 (rgb8) / HxW (mono8) array."""
    if isinstance(frame, CameraFrame):
        return frame
    if isinstance(frame, (bytes, bytearray, memoryview)):
        data = bytes(frame)
        if not data:
            raise ValueError("camera frame is empty")
        if len(data) > _MAX_BYTES:
            raise ValueError(f"camera frame of {len(data)} bytes exceeds {_MAX_BYTES} bytes")
        encoding, width, height = image_size(data)
        return CameraFrame(data, width, height, encoding, source=source)
    shape = getattr(frame, "shape", None)
    if shape is not None and hasattr(frame, "tobytes"):
        if len(shape) == 3 and shape[2] == 3:
            encoding = "rgb8"
        elif len(shape) == 2:
            encoding = "mono8"
        else:
            raise ValueError(f"image array must be HxWx3 (rgb8) or HxW (mono8), got {shape}")
        if str(getattr(frame, "dtype", "uint8")) != "uint8":
            raise ValueError(f"image array must be uint8, got {frame.dtype}")
        return CameraFrame(frame.tobytes(), int(shape[1]), int(shape[0]), encoding, source=source)
    raise ValueError(
        f"unsupported camera frame {type(frame).__name__}: give JPEG/PNG bytes, a CameraFrame, "
        "or a uint8 array of shape HxWx3 or HxW"
    )


def raw_image_frame(
    data: bytes | bytearray | memoryview,
    width: int,
    height: int,
    encoding: str,
    step: int,
    source: str = "camera",
) -> CameraFrame:
    """A sensor_msgs/Image (rgb8, bgr8, mono8) as a CameraFrame; row padding is removed.

    Raises ValueError naming what is wrong (encoding, sizes, data length).
    """
    channels = RAW_ENCODINGS.get(encoding)
    if channels is None:
        raise ValueError(
            f"unsupported image encoding {encoding!r}; supported: "
            f"{', '.join(RAW_ENCODINGS)} (or send sensor_msgs/CompressedImage)"
        )
    if not (0 < width <= _MAX_RAW_SIDE and 0 < height <= _MAX_RAW_SIDE):
        raise ValueError(f"image size {width}x{height} is out of range (1..{_MAX_RAW_SIDE} a side)")
    row = width * channels
    if step < row:
        raise ValueError(
            f"image step {step} is smaller than a {encoding} row of {width} pixels ({row} bytes)"
        )
    if len(data) != step * height:
        raise ValueError(
            f"image data has {len(data)} bytes; {height} rows of step {step} need {step * height}"
        )
    view = memoryview(data)
    if step == row:
        pixels = bytes(view)
    else:
        pixels = b"".join(view[r * step : r * step + row] for r in range(height))
    return CameraFrame(pixels, width, height, encoding, stamp=time.time(), source=source)


_PIL_MODES = {"rgb8": "RGB", "bgr8": "RGB", "mono8": "L"}


def encode_jpeg(frame: CameraFrame, max_side: int | None = None, quality: int = 80) -> bytes:
    """The frame as JPEG bytes, its longest side at most `max_side` pixels.

    A JPEG that needs no downscaling is returned as it is (no re-encoding). Needs Pillow
    (the `llm` or `web` extra): raises ImportError without it, ValueError for data that is not
    a decodable image of the frame's encoding.
    """
    small_enough = max_side is None or max(frame.width, frame.height) <= max_side
    if frame.encoding == "jpeg" and small_enough:
        return frame.data
    from PIL import Image  # imported here: only callers that show or send images need it

    image: Image.Image
    try:
        if frame.encoding in ("jpeg", "png"):
            image = Image.open(io.BytesIO(frame.data))
            image.load()
        elif frame.encoding in _PIL_MODES:
            image = Image.frombytes(
                _PIL_MODES[frame.encoding], (frame.width, frame.height), frame.data
            )
            if frame.encoding == "bgr8":
                blue, green, red = image.split()
                image = Image.merge("RGB", (red, green, blue))
        else:
            raise ValueError(f"camera frames in {frame.encoding!r} cannot be converted")
        image = image.convert("RGB")
        if max_side is not None:
            image.thumbnail((max_side, max_side))
        out = io.BytesIO()
        image.save(out, format="JPEG", quality=quality)
    except OSError as exc:  # Pillow's "cannot identify image file" and truncated data
        raise ValueError(f"the camera frame could not be decoded: {exc}") from exc
    return out.getvalue()
