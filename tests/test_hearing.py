"""Hearing (issue 27): a recording's container and length read without decoding, spoken stops,
and the transcription client's errors. The browser's own recordings are read in
tests/web/test_browser_speech.py; here the containers are built to their specifications."""

from __future__ import annotations

import struct

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from shadowhound.config import SpeechConfig
from shadowhound.hearing import AudioProblem, Transcriber, TranscriptionError, inspect, is_stop
from tests.web.test_speech_api import wav


def ogg_page(granule: int, packet: bytes, sequence: int) -> bytes:
    """One Ogg page holding `packet` (CRC left 0: the length reader does not check it)."""
    segments = [255] * (len(packet) // 255) + [len(packet) % 255]
    return (
        b"OggS"
        + struct.pack("<BBqIII", 0, 0, granule, 1, sequence, 0)
        + bytes([len(segments), *segments])
        + packet
    )


def opus(seconds: float, pre_skip: int = 312) -> bytes:
    head = b"OpusHead" + struct.pack("<BBHIhB", 1, 1, pre_skip, 48000, 0, 0)
    tags = b"OpusTags" + struct.pack("<I", 0) + struct.pack("<I", 0)
    last = int(seconds * 48000) + pre_skip
    return ogg_page(0, head, 0) + ogg_page(0, tags, 1) + ogg_page(last, b"\x00" * 40, 2)


def ebml(element: int, body: bytes, unknown: bool = False) -> bytes:
    id_bytes = element.to_bytes((element.bit_length() + 7) // 8, "big")
    size = b"\x01" + (b"\xff" * 7 if unknown else len(body).to_bytes(7, "big"))
    return id_bytes + size + body


def webm(cluster_ms: list[int], block_ms: int = 20) -> bytes:
    """A live-recorder WebM: Segment and Clusters of unknown size, no Duration."""
    header = ebml(0x1A45DFA3, ebml(0x4282, b"webm"))
    info = ebml(0x1549A966, ebml(0x2AD7B1, (1_000_000).to_bytes(3, "big")))
    clusters = b""
    for start in cluster_ms:
        blocks = b"".join(
            ebml(0xA3, b"\x81" + struct.pack(">h", t) + b"\x80" + b"\x00" * 10)
            for t in range(0, 1000, block_ms)
        )
        clusters += ebml(0x1F43B675, ebml(0xE7, start.to_bytes(4, "big")) + blocks, unknown=True)
    return header + ebml(0x18538067, info + clusters, unknown=True)


def test_lengths_are_read_from_each_container() -> None:
    assert inspect(wav(2.5), "audio/wav").seconds == pytest.approx(2.5)
    assert inspect(wav(1.0), "audio/x-wav; codecs=1").kind == "wav"
    assert inspect(opus(3.2), "audio/ogg;codecs=opus").seconds == pytest.approx(3.2)
    recording = webm([0, 1000, 2000])
    assert inspect(recording, "audio/webm;codecs=opus").seconds == pytest.approx(2.98, abs=0.01)
    assert inspect(recording, "audio/webm").content_type == "audio/webm"


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


@pytest.mark.parametrize(
    "said", ["stop", "Stop!", "STOP STOP", "halt.", "e-stop", "Emergency stop!", "stop now please"]
)
def test_a_spoken_stop_is_only_stop_words(said: str) -> None:
    assert is_stop(said)


@pytest.mark.parametrize(
    "said",
    [
        "walk until I say stop",
        "stop if you see a person",
        "go to the bus stop",
        "don't stop",
        "please",
        "",
        "stop and sit down",
    ],
)
def test_a_sentence_about_stopping_is_not_a_stop(said: str) -> None:
    assert not is_stop(said)


def test_the_client_says_what_is_missing_or_wrong() -> None:
    audio = inspect(wav(0.2), "audio/wav")
    with pytest.raises(TranscriptionError, match="speech.base_url") as off:
        Transcriber(SpeechConfig()).transcribe(wav(0.2), audio)
    assert off.value.status == 503
    down = Transcriber(SpeechConfig(base_url="http://127.0.0.1:9/v1", timeout=2))
    with pytest.raises(TranscriptionError, match="did not answer"):
        down.transcribe(wav(0.2), audio)
