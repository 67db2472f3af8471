"""What a recording is before anyone listens to it: its container and how long it lasts.

A browser's MediaRecorder sends WebM (Chromium) or Ogg (Firefox) with Opus; other clients send
WAV. The length is read from the container without decoding a sample, and no header is
trusted alone (meter.py): WAV is its PCM bytes at its own rate (wav.py); Ogg and WebM are
their packets, each Opus packet's own length, against the time the container stamps (ogg.py,
webm.py). Reading is linear in the bytes and stops as soon as the recording is too long. A
recording that is none of these, or that cannot be read, is refused saying so.
"""

from __future__ import annotations

import struct
from dataclasses import dataclass

from ..errors import AudioProblem, RecordingUnreadable
from .meter import MAX_SECONDS, Meter
from .ogg import read_ogg
from .wav import read_wav
from .webm import read_webm

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


def not_taken(content_type: str) -> str:
    """What to say of a Content-Type that is not a recording we take."""
    shown = base_type(content_type) or "none"
    return f"Content-Type {shown!r} is not a recording we take: send {ALLOWED}"


def inspect(data: bytes, content_type: str, max_seconds: float = MAX_SECONDS) -> Audio:
    """The recording's container and length; AudioProblem when it is not one we take, its
    RecordingTooLong as soon as it is read to be longer than `max_seconds`."""
    base = base_type(content_type)
    kind = KINDS.get(base)
    if kind is None:
        raise AudioProblem(not_taken(content_type))
    if not data:
        raise AudioProblem("the recording is empty")
    meter = Meter(max_seconds)
    try:
        _READERS[kind](data, meter)
    except (RecordingUnreadable, IndexError, struct.error) as exc:  # a reader's reason
        raise RecordingUnreadable(
            f"the recording is not a readable {kind.upper()} file ({exc})"
        ) from None
    if meter.seconds <= 0:
        raise AudioProblem("the recording holds no sound: hold the button and speak")
    return Audio(kind, meter.seconds, base)


_READERS = {"wav": read_wav, "ogg": read_ogg, "webm": read_webm}
