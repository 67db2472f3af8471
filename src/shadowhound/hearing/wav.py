"""A WAV's length: its PCM bytes at its own rate, never a header's word alone.

Only formats whose rate is fixed by the `fmt ` chunk are taken (integer PCM, float, A-law,
mu-law, and the extensible form of these), and that chunk must agree with itself: the block is
the channels times the sample's bytes, and the byte rate the sample rate times the block (a
byte rate of 4e9 beside 16 kHz mono is refused). The sound is then the `data` bytes actually
present (a size that claims more, or a streaming recorder's 0 or 0xFFFFFFFF, counts what is
there) at that rate: exact. Limits of plausibility: 1-8 channels, 1 Hz-768 kHz, 8-64 bits.
"""

from __future__ import annotations

import struct

from ..errors import RecordingUnreadable
from .meter import Meter

_PCM, _FLOAT, _ALAW, _MULAW, _EXTENSIBLE = 1, 3, 6, 7, 0xFFFE
_BITS = {_PCM: (8, 16, 24, 32), _FLOAT: (32, 64), _ALAW: (8,), _MULAW: (8,)}
MAX_CHANNELS, MAX_RATE = 8, 768_000


def read_wav(data: bytes, meter: Meter) -> None:
    if data[:4] != b"RIFF" or data[8:12] != b"WAVE":
        raise RecordingUnreadable("no RIFF/WAVE header")
    pos, byte_rate = 12, 0
    while pos + 8 <= len(data):
        meter.other()
        chunk, length = data[pos : pos + 4], struct.unpack_from("<I", data, pos + 4)[0]
        if chunk == b"fmt ":
            byte_rate = _byte_rate(data[pos + 8 : pos + 8 + length])
        elif chunk == b"data":
            if not byte_rate:
                raise RecordingUnreadable("its data chunk comes before a fmt chunk")
            present = len(data) - pos - 8
            size = present if length in (0, 0xFFFFFFFF) else min(length, present)
            meter.sound(size / byte_rate)
            return
        pos += 8 + length + (length & 1)
    raise RecordingUnreadable("no fmt or data chunk")


def _byte_rate(fmt: bytes) -> int:
    """Bytes a second of sound, from a `fmt ` chunk that agrees with itself."""
    if len(fmt) < 16:
        raise RecordingUnreadable(f"its fmt chunk has {len(fmt)} bytes; 16 at least")
    tag, channels, rate, byte_rate, block, bits = struct.unpack_from("<HHIIHH", fmt)
    if tag == _EXTENSIBLE and len(fmt) >= 26:
        tag = struct.unpack_from("<H", fmt, 24)[0]  # the sub-format's first two bytes
    if tag not in _BITS:
        raise RecordingUnreadable(f"format {tag:#x}: take PCM, float, A-law or mu-law")
    if not (1 <= channels <= MAX_CHANNELS and 1 <= rate <= MAX_RATE and bits in _BITS[tag]):
        raise RecordingUnreadable(
            f"{channels} channels of {bits} bits at {rate} Hz: take 1-{MAX_CHANNELS} channels "
            f"of {'/'.join(map(str, _BITS[tag]))} bits at 1-{MAX_RATE} Hz"
        )
    if block != channels * bits // 8 or byte_rate != rate * block:
        raise RecordingUnreadable(
            f"its fmt chunk disagrees with itself: {byte_rate} bytes a second and blocks of "
            f"{block}, where {rate} Hz x {channels} x {bits} bits make "
            f"{rate * channels * bits // 8}"
        )
    return int(byte_rate)
