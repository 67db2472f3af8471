"""Recordings read in reader processes (issue 32): the same answers as reading them here, the
refusals rebuilt as the same errors, and a reader that dies answered 503 and replaced."""

from __future__ import annotations

import os
import signal
from collections.abc import Iterator

import pytest

from shadowhound.errors import RecordingUnreadable
from shadowhound.hearing import AudioProblem, HearingBusy, RecordingTooLong, inspect, reading
from shadowhound.hearing.reading import Reader
from tests.recordings import huge_timecode_webm, opus, webm
from tests.web.test_speech_api import wav


@pytest.fixture
def reader() -> Iterator[Reader]:
    one = Reader()
    yield one
    one.stop()


def test_a_reader_answers_as_inspect_does(reader: Reader) -> None:
    for data, kind in [
        (wav(1.5), "audio/wav"),
        (opus(2.0), "audio/ogg"),
        (webm([0]), "audio/webm"),
    ]:
        assert reader.inspect(data, kind, 30.0) == inspect(data, kind, 30.0)
    with pytest.raises(RecordingTooLong) as long:
        reader.inspect(opus(5.0, granule=-1), "audio/ogg", 3.0)
    assert long.value.seconds > 3.0 and long.value.limit == 3.0 and not long.value.exact
    with pytest.raises(RecordingUnreadable, match="EBML allows 8"):
        reader.inspect(huge_timecode_webm(1000, 10), "audio/webm", 30.0)
    with pytest.raises(AudioProblem, match="not a recording we take"):
        reader.inspect(b"x", "text/plain", 30.0)


def test_a_dead_reader_is_replaced_and_a_silent_one_answered_503(
    reader: Reader, monkeypatch: pytest.MonkeyPatch
) -> None:
    assert reader.inspect(wav(0.5), "audio/wav", 30.0).seconds == pytest.approx(0.5)
    dead = reader.pid
    assert dead is not None
    os.kill(dead, signal.SIGKILL)
    os.waitpid(dead, 0)  # gone for sure
    assert reader.inspect(wav(0.5), "audio/wav", 30.0).seconds == pytest.approx(0.5)
    assert reader.pid not in (None, dead)
    # One that never answers (stopped) is ended at its time, the request answered 503.
    monkeypatch.setattr(reading, "ANSWER_SECONDS", 0.5)
    silent = reader.pid
    assert silent is not None
    os.kill(silent, signal.SIGSTOP)
    with pytest.raises(HearingBusy) as stopped:
        reader.inspect(wav(0.5), "audio/wav", 30.0)
    assert stopped.value.status == 503 and "say it again" in str(stopped.value)
    monkeypatch.undo()  # a new reader has its usual time to start
    assert reader.inspect(wav(0.5), "audio/wav", 30.0).seconds == pytest.approx(0.5)
    assert reader.pid not in (None, silent)
