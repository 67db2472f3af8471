"""How much sound an Opus packet holds, read from its first bytes (RFC 6716, section 3.1).

A decoder plays exactly what each packet's table-of-contents byte says: a frame of 2.5 to
60 ms, one, two or (code 3) the count in the second byte. Summing packets is therefore the
length a transcription server will hear, whatever a container's timestamps or granule claim.
"""

from __future__ import annotations

SHORTEST = 0.0025  # seconds: the shortest Opus frame; no packet holds less
LONGEST = 0.120  # seconds: the most one packet may hold (RFC 6716, 3.2.5)

# Frame length by configuration (the TOC's top five bits): SILK 10/20/40/60 ms for three
# bandwidths, hybrid 10/20 ms for two, CELT 2.5/5/10/20 ms for four.
_FRAME = (0.010, 0.020, 0.040, 0.060) * 3 + (0.010, 0.020) * 2 + (0.0025, 0.005, 0.010, 0.020) * 4


def packet_seconds(packet: bytes | memoryview) -> float:
    """The sound in one packet. A packet that cannot be decoded (empty, or a code-3 packet
    without a valid count) is taken as the longest a packet may be: a decoder may conceal it
    with that much, and a length read here must never be less than what is heard."""
    if not packet:
        return LONGEST
    toc = packet[0]
    frame = _FRAME[toc >> 3]
    code = toc & 3
    if code == 0:
        return frame
    if code in (1, 2):
        return 2 * frame
    if len(packet) < 2:
        return LONGEST
    count = packet[1] & 0x3F
    if count == 0 or count * frame > LONGEST + 1e-9:
        return LONGEST
    return count * frame
