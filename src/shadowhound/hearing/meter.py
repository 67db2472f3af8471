"""What reading one recording may find and spend: the sound it holds, the time its container
claims, and the elements walked to learn both.

A container's header may lie (a WebM Duration of NaN, an Ogg granule of -1, a WAV byte rate of
4e9), so no claim is taken alone. The length of a recording is the largest of:

- the sound its packets hold, counted packet by packet (an Opus packet from its own
  table-of-contents byte, which is what a decoder plays; a packet whose length cannot be read
  is taken as at least 2.5 ms, Opus's shortest frame),
- its bytes at the highest rate its codec reaches (`ceiling`, bytes a second: Vorbis at
  512 kbit/s, above its top quality in stereo), where packets do not say their length,
- the time its container stamps (timestamps, granule, Duration): finite and never negative.

Lying low gains nothing (the sound counted is what a transcription server hears), and lying
high only refuses the recording. Every reader stops as soon as the length is past the limit,
and walks at most `FREE_ELEMENTS` elements that hold no sound, plus two for each packet found:
its work is bounded by the limit and linear in the bytes, whatever they are.
"""

from __future__ import annotations

import math

from ..errors import RecordingTooLong, RecordingUnreadable
from .opus import SHORTEST

MAX_SECONDS = 300.0  # the most speech.max_seconds may be
FREE_ELEMENTS = 1024  # headers, tags, clusters, pages: more than a recording of any length has


class Meter:
    """The length found so far (see above); raises RecordingTooLong once it is past
    `max_seconds`, and RecordingUnreadable when the walk is past its bound."""

    def __init__(self, max_seconds: float = MAX_SECONDS) -> None:
        self.max_seconds = max_seconds
        self.heard = 0.0  # seconds of sound in the packets counted
        self.stamped = 0.0  # seconds the container's own time says
        self.audio_bytes = 0  # bytes of the packets counted
        self.ceiling: float | None = None  # bytes a second the codec never exceeds, if used
        self.packets = 0
        self.others = 0
        self.exact = False  # the length is the sound itself (PCM: bytes at its own rate)

    @property
    def seconds(self) -> float:
        bytes_bound = self.audio_bytes / self.ceiling if self.ceiling else 0.0
        return max(self.heard, self.stamped, bytes_bound)

    def packet(self, seconds: float, size: int) -> None:
        """One packet holding `seconds` of sound (at least Opus's shortest frame) in `size`
        bytes."""
        self.packets += 1
        self.heard += max(seconds, SHORTEST)
        self.audio_bytes += size
        self._check()

    def sound(self, seconds: float) -> None:
        """The recording's whole sound, known exactly (PCM: its bytes at its own rate)."""
        self.heard, self.exact = seconds, True
        self._check()

    def stamp(self, seconds: float, what: str) -> None:
        """A time the container claims for the end of its sound (`what` names it)."""
        if not math.isfinite(seconds) or seconds < 0:
            raise RecordingUnreadable(
                f"its {what} is {seconds!r} s: a length is finite and not negative"
            )
        self.stamped = max(self.stamped, seconds)
        self._check()

    def other(self) -> None:
        """One element, page or chunk that holds no sound."""
        self.others += 1
        if self.others > FREE_ELEMENTS + 2 * self.packets:
            raise RecordingUnreadable(
                f"more than {self.others - 1} elements beside {self.packets} packets of sound: "
                f"a recording has at most {FREE_ELEMENTS} plus two a packet"
            )

    def _check(self) -> None:
        seconds = self.seconds
        if seconds > self.max_seconds:
            raise RecordingTooLong(seconds, self.max_seconds, exact=self.exact)
