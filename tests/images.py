"""Small real image files for tests (no image library needed)."""

from __future__ import annotations

import struct


def tiny_jpeg(width: int, height: int) -> bytes:
    """A JPEG header with SOI, APP0 and SOF0 markers: enough for size detection."""
    app0 = b"\xff\xe0" + struct.pack(">H", 16) + b"JFIF\x00\x01\x01\x00\x00\x01\x00\x01\x00\x00"
    sof0 = b"\xff\xc0" + struct.pack(">HBHHB", 11, 8, height, width, 1) + b"\x01\x11\x00"
    return b"\xff\xd8" + app0 + sof0 + b"\xff\xd9"
