"""Recordings built to their containers' specifications, honest and crafted, for the hearing
tests and the speech benchmarks (WAV is tests.web.test_speech_api.wav)."""

from __future__ import annotations

import struct

# An Opus packet's table-of-contents byte: CELT fullband, one 20 ms frame (what browsers send).
OPUS_20MS = 0xF8


def ogg_page(granule: int, packet: bytes, sequence: int, flags: int = 0) -> bytes:
    """One Ogg page holding `packet` (CRC left 0: the length reader does not check it)."""
    segments = [255] * (len(packet) // 255) + [len(packet) % 255]
    return (
        b"OggS"
        + struct.pack("<BBqIII", 0, flags, granule, 1, sequence, 0)
        + bytes([len(segments), *segments])
        + packet
    )


def opus_head(pre_skip: int = 312) -> bytes:
    return b"OpusHead" + struct.pack("<BBHIhB", 1, 1, pre_skip, 48000, 0, 0)


def opus(seconds: float, pre_skip: int = 312, granule: int | None = None) -> bytes:
    """Ogg Opus of `seconds` in 20 ms packets, one a page, the granule counting them (or a
    last page's `granule` as given)."""
    tags = b"OpusTags" + struct.pack("<I", 0) + struct.pack("<I", 0)
    pages = [ogg_page(0, opus_head(pre_skip), 0), ogg_page(0, tags, 1)]
    count = max(1, round(seconds / 0.020))
    for i in range(count):
        at = pre_skip + (i + 1) * 960
        if granule is not None and i == count - 1:
            at = granule
        pages.append(ogg_page(at, bytes([OPUS_20MS]) + b"\x00" * 40, i + 2))
    return b"".join(pages)


def ebml(element: int, body: bytes, unknown: bool = False) -> bytes:
    id_bytes = element.to_bytes((element.bit_length() + 7) // 8, "big")
    size = b"\x01" + (b"\xff" * 7 if unknown else len(body).to_bytes(7, "big"))
    return id_bytes + size + body


def webm_head(codec: bytes = b"A_OPUS", scale: bytes = (1_000_000).to_bytes(3, "big")) -> bytes:
    """The EBML header, and a live Segment (unknown size) opening with Info and one track."""
    header = ebml(0x1A45DFA3, ebml(0x4282, b"webm"))
    info = ebml(0x1549A966, ebml(0x2AD7B1, scale))
    track = ebml(0xAE, ebml(0xD7, b"\x01") + ebml(0x83, b"\x02") + ebml(0x86, codec))
    return header + b"\x18\x53\x80\x67\x01" + b"\xff" * 7 + info + ebml(0x1654AE6B, track)


def block(ms: int, payload: bytes = bytes([OPUS_20MS]) + b"\x00" * 10) -> bytes:
    """A SimpleBlock of track 1 at `ms` after its cluster."""
    return ebml(0xA3, b"\x81" + struct.pack(">h", ms) + b"\x80" + payload)


def webm(cluster_ms: list[int], block_ms: int = 20) -> bytes:
    """A live-recorder WebM: Segment and Clusters of unknown size, no Duration, a second of
    20 ms Opus blocks in each cluster."""
    clusters = b""
    for start in cluster_ms:
        blocks = b"".join(block(t) for t in range(0, 1000, block_ms))
        clusters += ebml(0x1F43B675, ebml(0xE7, start.to_bytes(4, "big")) + blocks, unknown=True)
    return webm_head() + clusters


# -- crafted (issue 32) -------------------------------------------------------------------------


def huge_timecode_webm(timecode_bytes: int = 1_300_000, blocks: int = 60_000) -> bytes:
    """The issue's WebM: a cluster timecode of a million bytes, then 60,000 tiny blocks (it
    held the server 22-25 s: every block's time was a sum with that number)."""
    timecode = ebml(0xE7, b"\x7f" + b"\xff" * (timecode_bytes - 1))
    tiny = bytes([0xA3, 0x84, 0x81, 0x00, 0x01, 0x80]) * blocks
    cluster = b"\x1f\x43\xb6\x75\x01" + b"\xff" * 7 + timecode + tiny
    return webm_head() + cluster


def void_webm(size: int = 2_000_000) -> bytes:
    """A WebM whose body is nothing but tiny Void elements (it held the server 1.7 s)."""
    return webm_head() + bytes([0xEC, 0x81, 0x00]) * (size // 3)


def lying_wav(byte_rate: int = 4_000_000_000, seconds: float = 50.0) -> bytes:
    """16 kHz mono 16-bit PCM whose fmt claims another byte rate (so a 50 s recording read as
    0.0004 s)."""
    data = b"\x00\x01" * round(16000 * seconds)
    fmt = struct.pack("<HHIIHH", 1, 1, 16000, byte_rate, 2, 16)
    body = b"WAVE" + b"fmt " + struct.pack("<I", 16) + fmt + b"data"
    body += struct.pack("<I", len(data)) + data
    return b"RIFF" + struct.pack("<I", len(body)) + body


def encoded_opus(seconds: float, path: str) -> bytes | None:
    """A 440 Hz tone encoded by a real encoder: libsndfile's Ogg Opus (libopus) at 16 kHz,
    written to `path`; None where the library cannot write Opus."""
    import ctypes
    import ctypes.util
    import math

    name = ctypes.util.find_library("sndfile")
    if name is None:
        return None

    class Info(ctypes.Structure):
        _fields_ = [
            ("frames", ctypes.c_int64),
            ("samplerate", ctypes.c_int),
            ("channels", ctypes.c_int),
            ("format", ctypes.c_int),
            ("sections", ctypes.c_int),
            ("seekable", ctypes.c_int),
        ]

    sndfile = ctypes.CDLL(name)
    sndfile.sf_open.restype = ctypes.c_void_p
    sndfile.sf_write_short.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_int64]
    sndfile.sf_close.argtypes = [ctypes.c_void_p]
    rate, ogg_opus, write = 16000, 0x200000 | 0x0064, 0x20
    info = Info(0, rate, 1, ogg_opus, 0, 0)
    handle = sndfile.sf_open(path.encode(), write, ctypes.byref(info))
    if not handle:
        return None
    count = int(seconds * rate)
    tone = [int(8000 * math.sin(2 * math.pi * 440 * i / rate)) for i in range(count)]
    sndfile.sf_write_short(handle, (ctypes.c_short * count)(*tone), count)
    sndfile.sf_close(handle)
    with open(path, "rb") as recording:
        return recording.read()
