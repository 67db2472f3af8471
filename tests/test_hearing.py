"""Hearing (issues 27, 32): a recording's container and length read without decoding and
without trusting a header, and the transcription client's errors. The browser's own
recordings are read in tests/web/test_browser_speech.py; here the containers are built to their
specifications (tests/recordings.py). Spoken stops: tests/test_hearing_stop.py."""

from __future__ import annotations

import math
import struct
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from shadowhound.config import SpeechConfig
from shadowhound.errors import RecordingUnreadable
from shadowhound.hearing import (
    AudioProblem,
    RecordingTooLong,
    Transcriber,
    TranscriptionError,
    inspect,
)
from shadowhound.hearing.meter import FREE_ELEMENTS, Meter
from shadowhound.hearing.opus import LONGEST, SHORTEST, packet_seconds
from shadowhound.hearing.webm import read_webm
from tests.recordings import (
    OPUS_20MS,
    block,
    ebml,
    encoded_opus,
    huge_timecode_webm,
    lying_wav,
    opus,
    void_webm,
    webm,
    webm_head,
)
from tests.web.test_speech_api import wav


def test_lengths_are_read_from_each_container() -> None:
    assert inspect(wav(2.5), "audio/wav").seconds == pytest.approx(2.5)
    assert inspect(wav(1.0), "audio/x-wav; codecs=1").kind == "wav"
    assert inspect(opus(3.2), "audio/ogg;codecs=opus").seconds == pytest.approx(3.2)
    recording = webm([0, 1000, 2000])
    assert inspect(recording, "audio/webm;codecs=opus").seconds == pytest.approx(3.0)
    assert inspect(recording, "audio/webm").content_type == "audio/webm"


def test_a_real_encoders_ogg_opus_is_read_to_its_length(tmp_path: Path) -> None:
    """libopus through libsndfile, as Firefox's recorder uses libopus: what a real encoder
    writes (its page layout, pre-skip and last granule) reads as the sound it holds."""
    recording = encoded_opus(2.5, str(tmp_path / "tone.opus"))
    if recording is None:
        pytest.skip("libsndfile cannot write Ogg Opus here")
    assert inspect(recording, "audio/ogg").seconds == pytest.approx(2.5, abs=0.05)
    with pytest.raises(RecordingTooLong):
        inspect(recording, "audio/ogg", 2.0)


@pytest.mark.parametrize(
    ("data", "kind", "why"),
    [
        (b"", "audio/wav", "empty"),
        (b"RIFFxxxxWAVE", "audio/wav", "not a readable WAV"),
        (b"OggS" + b"\x00" * 40, "audio/ogg", "not a readable OGG"),
        (b"\x1a\x45\xdf\xa3\xff", "audio/webm", "not a readable WEBM"),
        (b"ID3\x03", "audio/mpeg", "'audio/mpeg' is not a recording we take"),
        (b"x", "", "'none' is not a recording we take"),
    ],
)
def test_what_cannot_be_read_is_refused_saying_why(data: bytes, kind: str, why: str) -> None:
    with pytest.raises(AudioProblem, match=why):
        inspect(data, kind)


@settings(max_examples=400, deadline=None)
@given(
    data=st.one_of(
        st.binary(max_size=300),
        st.builds(lambda b, cut: opus(1.0)[:cut] + b, st.binary(max_size=50), st.integers(0, 200)),
        st.builds(lambda b, cut: webm([0])[:cut] + b, st.binary(max_size=50), st.integers(0, 900)),
        st.builds(lambda b, cut: wav(0.1)[:cut] + b, st.binary(max_size=50), st.integers(0, 80)),
    ),
    kind=st.sampled_from(["audio/webm", "audio/ogg", "audio/wav", "text/plain"]),
)
def test_any_bytes_give_a_length_or_a_clear_refusal(data: bytes, kind: str) -> None:
    """Garbage, truncated and padded recordings never raise anything but AudioProblem, and a
    length read is a finite number of seconds, never negative."""
    try:
        audio = inspect(data, kind)
    except AudioProblem as exc:
        assert str(exc)
        return
    assert 0 <= audio.seconds < float("inf")


# -- issue 32: crafted recordings are refused in bounded work, and no header is trusted --------


def test_the_issues_webm_is_refused_at_its_timecode_before_any_block() -> None:
    """A cluster timecode of 1.3 MB, then 60,000 blocks: it held the server 22-25 s (each
    block's time a sum with that number), and a TimecodeScale beyond a float gave HTTP 500."""
    meter = Meter(30.0)
    with pytest.raises(RecordingUnreadable, match="1300000 bytes; EBML allows 8"):
        read_webm(huge_timecode_webm(), meter)
    assert meter.packets == 0 and meter.others < 20  # refused at the number, before blocks
    with pytest.raises(AudioProblem, match="not a readable WEBM file") as refused:
        inspect(huge_timecode_webm(), "audio/webm")
    assert not isinstance(refused.value, RecordingTooLong)  # a 422, with what was wrong


def test_element_floods_and_absurd_numbers_are_refused_in_bounded_work() -> None:
    voids = Meter(30.0)
    with pytest.raises(RecordingUnreadable, match=f"at most {FREE_ELEMENTS} plus two a packet"):
        read_webm(void_webm(), voids)  # 2 MB of 3-byte Void elements
    assert voids.others == FREE_ELEMENTS + 1
    # An 8-byte timecode near 2^64 and 60,000 empty blocks: too long after a few hundred.
    late = ebml(0xE7, b"\xff" * 8) + bytes([0xA3, 0x84, 0x81, 0x00, 0x01, 0x80]) * 60_000
    crafted = webm_head() + b"\x1f\x43\xb6\x75\x01" + b"\xff" * 7 + late
    meter = Meter(30.0)
    with pytest.raises(RecordingTooLong):
        read_webm(crafted, meter)
    assert meter.packets <= 30.0 / LONGEST + 1
    for scale, why in [(b"\x00", "TimecodeScale is 0"), (b"\x01" * 9, "9 bytes; EBML allows 8")]:
        with pytest.raises(AudioProblem, match=why):
            inspect(webm_head(scale=scale) + webm([0])[len(webm_head()) :], "audio/webm")
    huge_scale = webm_head(scale=b"\xff" * 8) + webm([0, 1000])[len(webm_head()) :]
    with pytest.raises(RecordingTooLong):  # a finite, absurd length: 413, never a 500
        inspect(huge_scale, "audio/webm", 30.0)


@pytest.mark.parametrize(
    ("recording", "kind", "why"),
    [
        (lying_wav(4_000_000_000), "audio/wav", "disagrees with itself: 4000000000 bytes"),
        (opus(50.0, granule=-1), "audio/ogg", "longer than 30 s"),
        (opus(50.0, granule=0), "audio/ogg", "longer than 30 s"),
        (opus(1.0, granule=-5), "audio/ogg", "granule position is -5"),
    ],
)
def test_a_header_that_claims_a_short_recording_is_not_believed(
    recording: bytes, kind: str, why: str
) -> None:
    """The issue's lies: a WAV byte rate of 4e9, an Ogg granule of -1; each was taken and up to
    1.9 MB forwarded."""
    with pytest.raises(AudioProblem, match=why):
        inspect(recording, kind, 30.0)


def _webm_with(blocks: int, cluster: int, scale: int, duration: float | None) -> bytes:
    info = ebml(0x2AD7B1, scale.to_bytes(8, "big"))
    if duration is not None:
        info += ebml(0x4489, struct.pack(">d", duration))
    head = webm_head()
    start = head.index(b"\x15\x49\xa9\x66")  # Info: replaced by the crafted one
    tracks = head.index(b"\x16\x54\xae\x6b")
    head = head[:start] + ebml(0x1549A966, info) + head[tracks:]
    body = ebml(0xE7, cluster.to_bytes(8, "big")) + b"".join(block(0) for _ in range(blocks))
    return head + ebml(0x1F43B675, body, unknown=True)


@settings(max_examples=150, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(
    packets=st.integers(1, 400),
    lie=st.one_of(
        st.builds(
            lambda g, s: ("ogg", g, s), st.integers(-(2**63), 2**63 - 1), st.integers(0, 65535)
        ),
        st.builds(
            lambda c, s, d: ("webm", c, s, d),
            st.integers(0, 2**64 - 1),
            st.integers(0, 2**64 - 1),
            st.none() | st.floats(allow_nan=True, allow_infinity=True),
        ),
    ),
)
def test_no_header_makes_a_recording_shorter_than_the_sound_it_holds(
    packets: int, lie: tuple
) -> None:
    """Whatever an Ogg granule, a WebM cluster time, TimecodeScale or Duration claims, the
    length read is at least the sound in the packets (20 ms each here) or the recording is
    refused; never a length that is not finite, never over the limit."""
    sound = packets * 0.020
    if lie[0] == "ogg":
        data, kind = opus(sound, pre_skip=lie[2], granule=lie[1]), "audio/ogg"
    else:
        data, kind = _webm_with(packets, lie[1], lie[2], lie[3]), "audio/webm"
    try:
        audio = inspect(data, kind, 5.0)
    except RecordingTooLong as exc:
        assert exc.seconds > 5.0
        return
    except AudioProblem:
        return
    assert math.isfinite(audio.seconds) and sound - 1e-6 <= audio.seconds <= 5.0


@settings(max_examples=150, deadline=None)
@given(
    samples=st.integers(1, 4000),
    byte_rate=st.just(32000) | st.integers(0, 2**32 - 1),
    declared=st.sampled_from([0, 0xFFFFFFFF]) | st.integers(0, 2**32 - 1),
)
def test_a_wav_is_its_bytes_at_its_own_rate(samples: int, byte_rate: int, declared: int) -> None:
    data = bytearray(lying_wav(byte_rate, samples / 16000))
    data[40:44] = struct.pack("<I", declared)  # the data chunk's size
    present = 2 * samples
    heard = present if declared in (0, 0xFFFFFFFF) else min(declared, present)
    try:
        audio = inspect(bytes(data), "audio/wav")
    except AudioProblem:
        assert byte_rate != 32000 or heard == 0  # only a lying fmt (or no sound) is refused
        return
    assert byte_rate == 32000 and audio.seconds == pytest.approx(heard / 32000)


def _mutated(draw: st.DrawFn) -> bytes:
    honest = draw(st.sampled_from([opus(0.5), webm([0]), wav(0.1), huge_timecode_webm(100, 50)]))
    data = bytearray(honest)
    for _ in range(draw(st.integers(1, 8))):
        at = draw(st.integers(0, len(data) - 1))
        how = draw(st.sampled_from(["set", "insert", "cut", "big"]))
        if how == "set":
            data[at] = draw(st.integers(0, 255))
        elif how == "insert":
            data[at:at] = draw(st.binary(min_size=1, max_size=16))
        elif how == "cut":
            del data[at : at + draw(st.integers(1, 64))]
        else:  # a size or number field of all ones: unknown, or the largest there is
            data[at : at + 8] = b"\x01" + b"\xff" * 7
        if not data:
            data = bytearray(b"\x00")
    return bytes(data)


@settings(max_examples=400, deadline=None)
@given(data=st.composite(_mutated)(), limit=st.floats(0.1, 300.0))
def test_mutated_recordings_give_a_bounded_length_or_a_clear_refusal(
    data: bytes, limit: float
) -> None:
    for kind in ("audio/webm", "audio/ogg", "audio/wav"):
        try:
            audio = inspect(data, kind, limit)
        except AudioProblem as exc:
            assert str(exc)
            continue
        assert math.isfinite(audio.seconds) and 0 < audio.seconds <= limit


@pytest.mark.parametrize(
    ("packet", "seconds"),
    [
        (bytes([OPUS_20MS]), 0.020),  # CELT fullband, one 20 ms frame
        (bytes([0x00]), 0.010),  # SILK narrowband 10 ms
        (bytes([0x1B]), 0.120),  # SILK 60 ms, two frames (code 3 would say more)
        (bytes([0xFB, 0x03]), 0.060),  # code 3: three 20 ms frames
        (bytes([0xFB, 0x07]), LONGEST),  # seven 20 ms frames: over 120 ms, not decodable
        (b"", LONGEST),
        (bytes([0x83]), LONGEST),  # code 3 without its count
        (bytes([0x80 | 0x03, 0x30]), 48 * SHORTEST),  # 48 frames of 2.5 ms
    ],
)
def test_an_opus_packet_holds_what_its_toc_byte_says(packet: bytes, seconds: float) -> None:
    assert packet_seconds(packet) == pytest.approx(seconds)


def test_the_client_says_what_is_missing_or_wrong() -> None:
    audio = inspect(wav(0.2), "audio/wav")
    with pytest.raises(TranscriptionError, match="speech.base_url") as off:
        Transcriber(SpeechConfig()).transcribe(wav(0.2), audio)
    assert off.value.status == 503
    down = Transcriber(SpeechConfig(base_url="http://127.0.0.1:9/v1", timeout=2))
    with pytest.raises(TranscriptionError, match="did not answer"):
        down.transcribe(wav(0.2), audio)
