"""A WebM recording's length: its blocks, element by element (EBML, RFC 8794; Matroska).

MediaRecorder's WebM (Chromium) has one Opus track, no Duration, and a Segment and Clusters of
unknown size, so the elements are walked flat: into the containers below, over everything
else by its size. One audio track, Opus or Vorbis. Opus: every block's packet's own length
(opus.py; a laced block's frames are each taken as the longest a packet holds); Vorbis: its
bytes at Vorbis's highest rate. The timestamps (cluster time plus the block's own, at the
segment's TimecodeScale) and a Duration are claims too: their span must be finite.

EBML numbers hold at most 8 bytes; an element that says more is refused before it is read,
so no number here grows past 64 bits.
"""

from __future__ import annotations

import struct

from ..errors import RecordingUnreadable
from .meter import Meter
from .ogg import VORBIS_CEILING
from .opus import LONGEST, packet_seconds

_EBML, _SEGMENT, _CLUSTER, _INFO, _TRACKS, _TRACK = (
    0x1A45DFA3,
    0x18538067,
    0x1F43B675,
    0x1549A966,
    0x1654AE6B,
    0xAE,
)
_BLOCK_GROUP, _SIMPLE_BLOCK, _BLOCK = 0xA0, 0xA3, 0xA1
_TIMECODE_SCALE, _DURATION, _CLUSTER_TIME, _CODEC, _TRACK_TYPE = (
    0x2AD7B1,
    0x4489,
    0xE7,
    0x86,
    0x83,
)
_CONTAINERS = {_SEGMENT, _CLUSTER, _INFO, _TRACKS, _TRACK, _BLOCK_GROUP}  # read into
_LIVE = {_SEGMENT, _CLUSTER}  # may be of unknown size (a recording being written)
_CODECS = {"A_OPUS": "opus", "A_VORBIS": "vorbis"}
_NAMES = {_TIMECODE_SCALE: "TimecodeScale", _CLUSTER_TIME: "the cluster Timecode"}
_AUDIO = 2  # TrackType of an audio track


def _vint(data: bytes, pos: int, most: int) -> tuple[int, int, bool]:
    """An EBML variable-length number at `pos`, at most `most` bytes: (value with its length
    marker, its length, whether it is all ones: an unknown size)."""
    if pos >= len(data):
        raise RecordingUnreadable(f"it ends inside an element at byte {pos}")
    first, length = data[pos], 1
    while length <= most and not first & (0x80 >> (length - 1)):
        length += 1
    if length > most or pos + length > len(data):
        raise RecordingUnreadable(f"bad EBML number at byte {pos}")
    value = int.from_bytes(data[pos : pos + length], "big")
    bare = value & ((1 << (7 * length)) - 1)
    return value, length, bare == (1 << (7 * length)) - 1


def _uint(raw: bytes, element: int) -> int:
    if len(raw) > 8:
        raise RecordingUnreadable(
            f"{_NAMES[element]} is a number of {len(raw)} bytes; EBML allows 8"
        )
    return int.from_bytes(raw, "big")


class _Walk:
    """The state of one walk: the scale, the track, and the span of the timestamps."""

    def __init__(self, meter: Meter) -> None:
        self.meter = meter
        self.scale = 1_000_000  # nanoseconds a tick (Matroska's default)
        self.duration = 0.0  # ticks, from Info's Duration
        self.cluster = 0
        self.codec = ""
        self.tracks = 0
        self.first: int | None = None  # the earliest block's time, in ticks

    def leaf(self, element: int, raw: bytes) -> None:
        if element in (_SIMPLE_BLOCK, _BLOCK):
            self._block(raw)
            return
        self.meter.other()
        if element == _TIMECODE_SCALE:
            self.scale = _uint(raw, element)
            if self.scale == 0:
                raise RecordingUnreadable("its TimecodeScale is 0; a tick is at least 1 ns")
        elif element == _CLUSTER_TIME:
            self.cluster = _uint(raw, element)
        elif element == _DURATION:
            if len(raw) not in (4, 8):
                raise RecordingUnreadable(f"its Duration has {len(raw)} bytes; a float has 4 or 8")
            self.duration = struct.unpack(">f" if len(raw) == 4 else ">d", raw)[0]
            self.meter.stamp(self.duration * self.scale / 1e9, "Duration")
        elif element == _CODEC:
            name = raw.decode("ascii", "replace")
            self.codec = _CODECS.get(name, "")
            if not self.codec:
                raise RecordingUnreadable(
                    f"its codec is {name[:32]!r}: take Opus (what browsers record)"
                )
            if self.codec == "vorbis":
                self.meter.ceiling = VORBIS_CEILING
        elif element == _TRACK_TYPE and int.from_bytes(raw[:8], "big") != _AUDIO:
            raise RecordingUnreadable(
                "it has a track that is not audio; a recording has one audio track"
            )

    def track(self) -> None:
        self.tracks += 1
        if self.tracks > 1:
            raise RecordingUnreadable("it has more than one track; a recording has one audio track")

    def _block(self, raw: bytes) -> None:
        if not self.codec:
            raise RecordingUnreadable("a block comes before the track that says its codec")
        _track, n, _ = _vint(raw, 0, 8) if raw else (0, 0, False)
        if len(raw) < n + 3:
            self.meter.packet(LONGEST, len(raw))  # too short to say: the most it could hold
            return
        time = self.cluster + struct.unpack_from(">h", raw, n)[0]
        flags, payload = raw[n + 2], raw[n + 3 :]
        if flags & 0x06:  # laced: several frames; each taken as the longest a packet holds
            frames = payload[0] + 1 if payload else 1
            for _ in range(frames):
                self.meter.packet(LONGEST, len(payload) // frames)
            heard = frames * LONGEST
        else:
            heard = packet_seconds(payload) if self.codec == "opus" else 0.0
            self.meter.packet(heard, len(payload))
        self.first = time if self.first is None else min(self.first, time)
        span = (time - self.first) * self.scale / 1e9 + heard
        self.meter.stamp(span, "timestamps' span")


def read_webm(data: bytes, meter: Meter) -> None:
    if data[:4] != b"\x1a\x45\xdf\xa3":
        raise RecordingUnreadable("no EBML header")
    walk = _Walk(meter)
    pos = 0
    while pos < len(data):
        element, n, _ = _vint(data, pos, 4)
        size, m, unknown = _vint(data, pos + n, 8)
        size &= (1 << (7 * m)) - 1
        body = pos + n + m
        if element in _CONTAINERS:
            if unknown and element not in _LIVE:
                raise RecordingUnreadable(f"element {element:#x} of unknown size")
            meter.other()
            if element == _TRACK:
                walk.track()
            pos = body  # its children follow
            continue
        if unknown:
            raise RecordingUnreadable(f"element {element:#x} of unknown size")
        if element != _EBML:
            walk.leaf(element, data[body : body + size])  # elements do not overlap: linear
        else:
            meter.other()
        pos = body + size
