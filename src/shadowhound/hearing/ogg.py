"""An Ogg recording's length: its packets, page by page (RFC 3533; Opus in Ogg, RFC 7845).

One logical stream of Opus (what Firefox records) or Vorbis. The pages must follow each other
from the first byte to the last, and a packet may run over pages as the lacing says. Opus:
every audio packet's own length (opus.py); Vorbis: its bytes at Vorbis's highest rate. Each
page's granule position is also a claim (Opus at 48 kHz after its pre-skip, Vorbis at its
header's rate): -1 means no packet ends on that page; another negative one is refused.
"""

from __future__ import annotations

import struct

from ..errors import RecordingUnreadable
from .meter import Meter
from .opus import packet_seconds

VORBIS_CEILING = 64_000  # bytes a second: 512 kbit/s, above Vorbis's top quality in stereo
_HEAD = 64  # bytes kept of each packet: enough for the codec headers and an Opus TOC
_PAGE = struct.Struct("<4sBBqIIIB")


class _Stream:
    """The one logical stream: which codec, and the packets seen so far."""

    def __init__(self, meter: Meter) -> None:
        self.meter = meter
        self.codec = ""
        self.rate, self.skip = 48_000, 0
        self.count = 0  # packets finished

    def packet(self, head: bytes, size: int) -> None:
        n, self.count = self.count, self.count + 1
        if n == 0:
            self._identify(head)
        elif self.codec == "opus" and n >= 2:  # after OpusHead and OpusTags
            self.meter.packet(packet_seconds(head), size)
        elif self.codec == "vorbis" and n >= 3:  # after identification, comment and setup
            self.meter.packet(0.0, size)
        else:
            self.meter.other()

    def granule(self, value: int) -> None:
        if value == -1 or self.count < 1:
            return
        if value < 0:
            raise RecordingUnreadable(
                f"a page's granule position is {value}; it may not be negative"
            )
        self.meter.stamp(max(0, value - self.skip) / self.rate, "granule position")

    def _identify(self, head: bytes) -> None:
        if head.startswith(b"OpusHead") and len(head) >= 19:
            self.codec, self.skip = "opus", struct.unpack_from("<H", head, 10)[0]
        elif head[:7] == b"\x01vorbis" and len(head) >= 30:
            self.codec, self.rate = "vorbis", struct.unpack_from("<I", head, 12)[0]
            if not 1 <= self.rate <= 768_000:
                raise RecordingUnreadable(f"Vorbis at {self.rate} Hz: take 1-768000 Hz")
            self.meter.ceiling = VORBIS_CEILING
        else:
            raise RecordingUnreadable("its first packet is neither Opus nor Vorbis")
        self.meter.other()


def read_ogg(data: bytes, meter: Meter) -> None:
    if data[:4] != b"OggS":
        raise RecordingUnreadable("no Ogg page at the start")
    stream, serial = _Stream(meter), None
    head, size, open_packet = b"", 0, False
    pos = 0
    while pos < len(data):
        if len(data) - pos < _PAGE.size:
            raise RecordingUnreadable(f"the page at byte {pos} is cut short")
        capture, version, flags, granule, number, _seq, _crc, segments = _PAGE.unpack_from(
            data, pos
        )
        if capture != b"OggS" or version != 0:
            raise RecordingUnreadable(f"no Ogg page at byte {pos}")
        if serial is None:
            serial = number
        elif number != serial:
            raise RecordingUnreadable("it holds more than one stream; a recording has one")
        table = data[pos + _PAGE.size : pos + _PAGE.size + segments]
        body = pos + _PAGE.size + segments
        end = body + sum(table)
        if len(table) < segments or end > len(data):
            raise RecordingUnreadable(f"the page at byte {pos} is cut short")
        if bool(flags & 1) != open_packet:
            raise RecordingUnreadable(
                f"the page at byte {pos} does not continue its packet as it says"
            )
        meter.other()
        at = body
        for lace in table:
            if len(head) < _HEAD:
                head += data[at : at + min(lace, _HEAD - len(head))]
            size += lace
            at += lace
            open_packet = lace == 255
            if not open_packet:
                stream.packet(head, size)
                head, size = b"", 0
        stream.granule(granule)
        pos = end
    if open_packet:  # the last packet never ended: count what there is of it
        stream.packet(head, size)
