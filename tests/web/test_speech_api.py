"""Push-to-talk over HTTP (issue 27): `POST /api/speech` on a real server with a scripted
OpenAI-compatible transcription server, judged by the simulated robot's state."""

from __future__ import annotations

import io
import math
import struct
import wave
from collections.abc import Callable

import httpx
import pytest

from shadowhound.web import WebServer
from tests.speech_server import ScriptedTranscriber, status
from tests.web.conftest import make_agent, wait_for


def wav(seconds: float, rate: int = 16000) -> bytes:
    """A mono 16-bit WAV of a 440 Hz tone, `seconds` long."""
    out = io.BytesIO()
    with wave.open(out, "wb") as w:
        w.setnchannels(1)
        w.setsampwidth(2)
        w.setframerate(rate)
        frames = int(seconds * rate)
        w.writeframes(
            b"".join(
                struct.pack("<h", int(8000 * math.sin(2 * math.pi * 440 * i / rate)))
                for i in range(frames)
            )
        )
    return out.getvalue()


def post(server: WebServer, body: bytes, kind: str = "audio/wav") -> httpx.Response:
    return httpx.post(
        server.url + "/api/speech", content=body, headers={"content-type": kind}, timeout=30
    )


def test_a_spoken_mission_runs_and_the_recording_reaches_the_server_as_sent(
    serve: Callable[..., WebServer], heard: ScriptedTranscriber
) -> None:
    agent = make_agent(speech={"base_url": heard.url, "language": "en"})
    server = serve(agent)
    heard.script("Walk forward one meter.")
    recording = wav(1.5)
    reply = post(server, recording)
    assert reply.status_code == 202, reply.text
    answer = reply.json()
    assert answer["transcript"] == "Walk forward one meter."
    record = wait_for(
        lambda: (r := httpx.get(server.url + answer["url"]).json())["state"] == "finished" and r,
        15,
        "the spoken mission to finish",
    )
    assert record["success"] and record["command"] == "Walk forward one meter."
    assert agent.robot.get_state().x == pytest.approx(1.0, abs=0.01)
    [request] = heard.requests
    assert request.file == recording and request.file_type == "audio/wav"
    assert request.filename == "speech.wav"
    assert request.fields == {"model": "whisper-1", "response_format": "json", "language": "en"}


def test_a_spoken_stop_latches_the_estop_before_anything_is_planned(
    serve: Callable[..., WebServer], heard: ScriptedTranscriber
) -> None:
    agent = make_agent(time_scale=1.0, speech={"base_url": heard.url})
    server = serve(agent)
    heard.script("walk backward 3 meters", "Stop!")
    assert post(server, wav(1.0)).status_code == 202
    wait_for(lambda: agent.robot.get_state().vx < -0.1, 10, "the walk")
    reply = post(server, wav(0.5))
    assert reply.status_code == 200 and reply.json()["estop"] is True, reply.text
    assert agent.estop_latched
    # Stopped before the answer was written: the robot's true velocity is zero already.
    assert agent.robot.get_state().vx == 0.0
    later = post(server, wav(0.5))  # "Stop!" again: still the e-stop, nothing planned
    assert later.json()["estop"] is True


def test_while_the_robot_walks_a_stop_said_first_stops_it_and_at_rest_it_is_a_mission(
    serve: Callable[..., WebServer], heard: ScriptedTranscriber
) -> None:
    """Issue 32: "Stop! Turn around." while walking would queue behind the walk; it stops,
    and says what was not run. At rest, "Stop, then sit down" is a mission as before."""
    agent = make_agent(time_scale=1.0, speech={"base_url": heard.url})
    server = serve(agent)
    heard.script("walk backward 3 meters", "Stop! Turn around.", "Stop, then sit down")
    assert post(server, wav(1.0)).status_code == 202
    wait_for(lambda: agent.robot.get_state().vx < -0.1, 10, "the walk")
    reply = post(server, wav(0.5))
    assert reply.status_code == 200, reply.text
    answer = reply.json()
    assert answer["estop"] is True and answer["not_run"] == "Turn around."
    assert agent.robot.get_state().vx == 0.0 and agent.estop_latched
    agent.release_estop()
    wait_for(lambda: not agent.robot.get_state().is_moving, 10, "the robot at rest")
    at_rest = post(server, wav(0.5))
    assert at_rest.status_code == 202 and at_rest.json()["mission_id"], at_rest.text


@pytest.mark.parametrize(
    "said",
    ["walk forward until I say stop", "stop if you see a person and walk forward 1 meter"],
)
def test_a_sentence_that_mentions_stop_is_a_mission(
    serve: Callable[..., WebServer], heard: ScriptedTranscriber, said: str
) -> None:
    agent = make_agent(speech={"base_url": heard.url})
    server = serve(agent)
    heard.script(said)
    reply = post(server, wav(1.0))
    assert reply.status_code == 202 and reply.json()["mission_id"], reply.text
    assert reply.json()["transcript"] == said
    assert "estop" not in reply.json() and not agent.estop_latched, reply.text


def test_confirm_returns_the_transcript_and_runs_nothing(
    serve: Callable[..., WebServer], heard: ScriptedTranscriber
) -> None:
    agent = make_agent(speech={"base_url": heard.url, "confirm": True})
    server = serve(agent)
    heard.script("sit down")
    answer = post(server, wav(1.0)).json()
    assert answer == {"transcript": "sit down", "confirm": True, "mission_id": None}
    assert agent.history == []


def test_recordings_that_cannot_be_used_are_refused_saying_why(
    serve: Callable[..., WebServer], heard: ScriptedTranscriber
) -> None:
    agent = make_agent(speech={"base_url": heard.url, "max_seconds": 20, "max_bytes": 400_000})
    server = serve(agent)
    long = post(server, wav(600.0, rate=200))  # ten minutes (small: a low rate)
    assert long.status_code == 413 and "600 s long; at most 20 s" in long.json()["detail"]
    big = post(server, wav(15.0))  # 480 kB
    assert big.status_code == 413 and "speech.max_bytes" in big.json()["detail"]
    text = post(server, b"hello", "text/plain")
    assert text.status_code == 415 and "audio/webm, audio/ogg or audio/wav" in text.text
    broken = post(server, b"RIFF....WAVEjunk")
    assert broken.status_code == 422 and "not a readable WAV" in broken.json()["detail"]
    assert post(server, b"").status_code == 422
    heard.script("")
    silent = post(server, wav(1.0))
    assert silent.status_code == 422 and "nothing was heard" in silent.json()["detail"]
    assert len(heard.requests) == 1  # only the silent one was sent on
    assert agent.history == [] and agent.robot.get_state().x == 0.0


def test_without_a_transcription_server_it_says_how_to_set_one_up(
    serve: Callable[..., WebServer], heard: ScriptedTranscriber
) -> None:
    server = serve(make_agent())
    info = httpx.get(server.url + "/api/speech").json()
    assert info["configured"] is False and "speech.base_url" in info["why"]
    reply = post(server, wav(1.0))
    assert reply.status_code == 503 and "SHADOWHOUND_SPEECH__BASE_URL" in reply.text
    # A server that is down, or answers an error, is named.
    down = serve(make_agent(speech={"base_url": "http://127.0.0.1:9/v1"}))
    reply = post(down, wav(1.0))
    assert reply.status_code == 503 and "did not answer" in reply.json()["detail"]
    failing = serve(make_agent(speech={"base_url": heard.url}))
    heard.script(status(401, '{"error": "bad key"}'))
    reply = post(failing, wav(1.0))
    assert reply.status_code == 502 and "HTTP 401" in reply.text and "api_key_env" in reply.text
