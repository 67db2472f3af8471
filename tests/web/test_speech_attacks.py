"""Nothing a client sends holds up the stop (issue 32), on a real server with a scripted
transcription server: crafted recordings are refused in bounded work with a clear answer, a
client trickling its upload is answered 408 and holds nothing, the e-stop is answered while
transcriptions hang, and a spoken stop is heard ahead of the transcriptions queued before it.
The robot is judged by the simulator's state; nothing here waits on time but for answers."""

from __future__ import annotations

import socket
import threading
from collections.abc import Callable

import httpx
import pytest

from shadowhound.web import WebServer
from tests.recordings import huge_timecode_webm, lying_wav, opus, void_webm
from tests.speech_server import ScriptedTranscriber
from tests.web.conftest import make_agent, wait_for
from tests.web.test_speech_api import post, wav

Serve = Callable[..., WebServer]


@pytest.mark.parametrize(
    ("recording", "kind", "status", "why"),
    [
        (huge_timecode_webm(), "audio/webm", 422, "1300000 bytes; EBML allows 8"),
        (void_webm(1_900_000), "audio/webm", 422, "at most 1024 plus two a packet"),
        (lying_wav(4_000_000_000), "audio/wav", 422, "disagrees with itself"),
        (opus(50.0, granule=-1), "audio/ogg", 413, "longer than 30 s"),
    ],
)
def test_crafted_recordings_are_refused_saying_why_and_never_sent_on(
    serve: Serve, heard: ScriptedTranscriber, recording: bytes, kind: str, status: int, why: str
) -> None:
    """The issue's crafted uploads: the 1.7 MB WebM held the server 22-25 s and an oversized
    TimecodeScale gave HTTP 500; the lying headers were taken and forwarded."""
    server = serve(make_agent(speech={"base_url": heard.url}))
    reply = post(server, recording, kind)
    assert reply.status_code == status, reply.text
    assert why in reply.json()["detail"]
    assert heard.requests == []  # nothing went to the transcription server


def test_the_estop_is_answered_while_transcriptions_hang_and_a_spoken_stop_goes_first(
    serve: Serve, heard: ScriptedTranscriber
) -> None:
    """40 long recordings whose transcriptions hang at the server, then "Stop!": the e-stop
    button is answered, and the spoken stop is transcribed and latches the e-stop, while every
    one of the 40 is still unanswered (before, a spoken "STOP!" waited behind six slow ones)."""
    agent = make_agent(time_scale=1.0, speech={"base_url": heard.url})
    server = serve(agent)
    long, short = wav(5.0, rate=8000), wav(0.5)
    heard.hold = lambda request: len(request.file) > 50_000
    heard.answer = lambda request: "Stop!" if len(request.file) < 50_000 else "sit down"
    walk = httpx.post(server.url + "/api/mission", json={"command": "walk backward 3 meters"})
    assert walk.status_code == 202
    wait_for(lambda: agent.robot.get_state().vx < -0.1, 10, "the walk")
    answers: list[int] = []
    senders = [
        threading.Thread(target=lambda: answers.append(post(server, long).status_code))
        for _ in range(40)
    ]
    for sender in senders:
        sender.start()
    with heard.answered:
        assert heard.answered.wait_for(lambda: heard.held >= 2, 30), "no transcription hung"
    pressed = httpx.post(server.url + "/api/estop", timeout=30)
    assert pressed.status_code == 200 and pressed.json()["estop"] is True
    agent.release_estop()
    httpx.post(server.url + "/api/mission", json={"command": "walk backward 3 meters"})
    wait_for(lambda: agent.robot.get_state().vx < -0.1, 10, "the walk again")
    spoken = post(server, short)
    assert spoken.status_code == 200 and spoken.json()["estop"] is True, spoken.text
    assert agent.robot.get_state().vx == 0.0 and agent.estop_latched
    assert not heard.release.is_set() and all(r.file != long for r in heard.requests)
    heard.release.set()
    for sender in senders:
        sender.join(60)
    assert 429 in answers  # the queue is bounded: the oldest were answered at once


def test_a_trickled_upload_is_answered_408_and_closed_while_the_estop_is_answered(
    serve: Serve, heard: ScriptedTranscriber
) -> None:
    agent = make_agent(speech={"base_url": heard.url, "upload_timeout": 1.0})
    server = serve(agent)
    trickle = socket.create_connection((server.host, server.port), timeout=60)
    trickle.sendall(
        b"POST /api/speech HTTP/1.1\r\nHost: 127.0.0.1\r\nContent-Type: audio/wav\r\n"
        b"Content-Length: 100000\r\n\r\n" + wav(0.1)[:100]
    )
    pressed = httpx.post(server.url + "/api/estop", timeout=30)
    assert pressed.status_code == 200 and pressed.json()["estop"] is True
    answer = b""
    try:
        while chunk := trickle.recv(65536):  # the server answers, then closes the connection
            answer += chunk
            trickle.sendall(b"\x00")  # still trickling: it must not keep the connection open
    except (ConnectionResetError, BrokenPipeError):
        pass  # closed while this client still sent: as closed as can be
    trickle.close()
    assert answer.startswith(b"HTTP/1.1 408"), answer[:200]
    assert b"did not arrive within 1 s (speech.upload_timeout)" in answer
    assert heard.requests == []
