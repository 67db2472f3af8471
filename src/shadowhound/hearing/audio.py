"""What a recording is before anyone listens to it: its container and how long it lasts.

A browser's MediaRecorder sends WebM (Chromium) or Ogg (Firefox) with Opus; other clients send
WAV. The length is read from the container itself, without decoding a sample: WAV from its
`fmt ` byte rate and `data` size; Ogg from the last page's granule position (Opus counts
48 kHz samples after its pre-skip; Vorbis at the rate in its first header); WebM from the
latest block's time (cluster timecode plus the block's own, at the segment's timecode
scale), since MediaRecorder's WebM has no Duration and elements of unknown size. A recording
that is none of these, or that cannot be read, is refused saying so.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from ..errors import AudioProblem

KINDS = {
    "audio/webm": "webm",
    "video/webm": "webm",  # some browsers label an audio-only recording so
    "audio/ogg": "ogg",
    "application/ogg": "ogg",
    "audio/wav": "wav",
    "audio/x-wav": "wav",
    "audio/wave": "wav",
    "audio/vnd.wave": "wav",
}
ALLOWED = "audio/webm, audio/ogg or audio/wav"


@dataclass(frozen=True)
class Audio:
    kind: str  # webm | ogg | wav
    seconds: float
    content_type: str  # the base type, without parameters ("audio/webm")

    @property
    def filename(self) -> str:
        return f"speech.{self.kind}"


def base_type(content_type: str) -> str:
    """`audio/webm;codecs=opus` -> `audio/webm`."""
    return (content_type or "").split(";", 1)[0].strip().lower()


def taken(content_type: str) -> bool:
    """Whether a Content-Type is a recording we take (its length still to be read)."""
    return base_type(content_type) in KINDS


def inspect(data: bytes, content_type: str) -> Audio:
    """The recording's container and length; AudioProblem when it is not one we take."""
    base = base_type(content_type)
    kind = KINDS.get(base)
    if kind is None:
        shown = base or "none"
        raise AudioProblem(f"Content-Type {shown!r} is not a recording we take: send {ALLOWED}")
    if not data:
        raise AudioProblem("the recording is empty")
    reader = {"wav": _wav_seconds, "ogg": _ogg_seconds, "webm": _webm_seconds}[kind]
    try:
        seconds = reader(data)
    except (IndexError, struct.error, ValueError, ZeroDivisionError) as exc:
        raise AudioProblem(f"the recording is not a readable {kind.upper()} file ({exc})") from exc
    return Audio(kind, seconds, base)


# -- WAV ---------------------------------------------------------------------------------------


def _wav_seconds(data: bytes) -> float:
    if data[:4] != b"RIFF" or data[8:12] != b"WAVE":
        raise ValueError("no RIFF/WAVE header")
    pos, byte_rate, size = 12, 0, None
    while pos + 8 <= len(data):
        chunk, length = data[pos : pos + 4], struct.unpack_from("<I", data, pos + 4)[0]
        if chunk == b"fmt ":
            byte_rate = struct.unpack_from("<I", data, pos + 16)[0]
        elif chunk == b"data":
            # A recorder that streams writes 0 or 0xFFFFFFFF here: the data runs to the end.
            size = length if 0 < length < 0xFFFFFFFF else len(data) - pos - 8
            break
        pos += 8 + length + (length & 1)
    if not byte_rate or size is None:
        raise ValueError("no fmt or data chunk")
    return size / byte_rate


# -- Ogg ---------------------------------------------------------------------------------------


def _ogg_seconds(data: bytes) -> float:
    if data[:4] != b"OggS":
        raise ValueError("no Ogg page at the start")
    first = data[27 + data[26] :]  # the first packet, after the page's segment table
    if first.startswith(b"OpusHead"):
        rate, skip = 48000, struct.unpack_from("<H", first, 10)[0]
    elif first[1:7] == b"vorbis":
        rate, skip = struct.unpack_from("<I", first, 12)[0], 0
    else:
        raise ValueError("neither Opus nor Vorbis")
    last = data.rfind(b"OggS")
    granule = struct.unpack_from("<q", data, last + 6)[0]
    return float(max(0, granule - skip) / rate)


# -- WebM (EBML) -------------------------------------------------------------------------------

_SEGMENT, _CLUSTER, _INFO, _BLOCK_GROUP = 0x18538067, 0x1F43B675, 0x1549A966, 0xA0
_CONTAINERS = {_SEGMENT, _CLUSTER, _INFO, _BLOCK_GROUP}  # read into, not skipped
_TIMECODE_SCALE, _DURATION, _CLUSTER_TIME, _SIMPLE_BLOCK, _BLOCK = (
    0x2AD7B1,
    0x4489,
    0xE7,
    0xA3,
    0xA1,
)


def _vint(data: bytes, pos: int, keep_marker: bool) -> tuple[int, int, bool]:
    """An EBML variable-length integer at `pos`: (value, its length, all ones = unknown)."""
    first = data[pos]
    length = 1
    while length <= 8 and not first & (0x80 >> (length - 1)):
        length += 1
    if length > 8:
        raise ValueError(f"bad EBML number at byte {pos}")
    value = first if keep_marker else first & (0xFF >> length)
    for b in data[pos + 1 : pos + length]:
        value = (value << 8) | b
    unknown = not keep_marker and value == (1 << (7 * length)) - 1
    return value, length, unknown


def _uint(raw: bytes) -> int:
    return int.from_bytes(raw, "big")


def _webm_seconds(data: bytes) -> float:
    if data[:4] != b"\x1a\x45\xdf\xa3":
        raise ValueError("no EBML header")
    scale, duration, cluster, latest = 1_000_000, 0.0, 0, 0
    pos = 0
    while pos < len(data):
        element, n, _ = _vint(data, pos, keep_marker=True)
        size, m, unknown = _vint(data, pos + n, keep_marker=False)
        body = pos + n + m
        if element in _CONTAINERS:
            pos = body  # its children follow (its size may be unknown: a live recording)
            continue
        if unknown:
            raise ValueError(f"element {element:#x} of unknown size")
        raw = data[body : body + size]
        if element == _TIMECODE_SCALE:
            scale = _uint(raw)
        elif element == _DURATION and size in (4, 8):
            duration = struct.unpack(">f" if size == 4 else ">d", raw)[0]
        elif element == _CLUSTER_TIME:
            cluster = _uint(raw)
        elif element in (_SIMPLE_BLOCK, _BLOCK) and size >= 4:
            _track, t = _vint(raw, 0, keep_marker=False)[:2]
            latest = max(latest, cluster + struct.unpack_from(">h", raw, t)[0])
        pos = body + size
    return max(duration, float(latest)) * scale / 1e9
