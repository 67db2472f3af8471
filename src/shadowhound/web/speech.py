"""Push-to-talk: `POST /api/speech` takes a recording, has it transcribed and runs what was
said as a mission (or, when the words only say stop, in any of the ways hearing/commands.py
knows, latches the e-stop at once, before any planning). `GET /api/speech` tells the page
whether it is set up.

The recording's size is limited by the gate (`speech.max_bytes`, and the time it may take to
arrive, `speech.upload_timeout`) and its length here, read from the container
(`speech.max_seconds`); it is sent to the configured server and never kept. Reading and
transcribing run on the app's `Ears`, lanes of their own (hearing/lanes.py): the event loop,
which answers the e-stop, never waits on them. The transcript is the mission's command,
stored only where missions are (the history, when it is on). With `speech.confirm` the
transcript comes back to be confirmed by a person and nothing runs.
"""

from __future__ import annotations

import asyncio
from dataclasses import dataclass
from functools import partial
from typing import Any

from fastapi import APIRouter, Request

from ..admission import ESTOP_LATCHED, mission_text_problem
from ..config import SpeechConfig
from ..errors import HearingBusy, RecordingTooLong, RobotError
from ..hearing import (
    ALLOWED,
    AudioProblem,
    Lanes,
    Transcriber,
    TranscriptionError,
    is_stop,
    taken,
)
from ..hearing import not_configured as speech_off
from ..hearing.audio import not_taken
from ..hearing.commands import leading_stop
from ..hearing.reading import READERS, Readers
from ..worker import TELEOP_BUSY
from .api import WebContext, ctx
from .models import Problem
from .responses import StrictJSON

PATH = "/api/speech"
router = APIRouter(prefix="/api")

# A short recording (a spoken stop is about a second) goes first; these are what "short" is.
URGENT_SECONDS = 4.0
URGENT_BYTES = 256_000  # 4 s of 16-bit stereo at 32 kHz; an Opus recording of 4 s is ~20 kB
TRANSCRIBERS, RESERVED, WAITING = 2, 1, 8  # transcriptions at once (+ for short ones), queued
READ_SECONDS = 10.0  # a recording not read within this is stale (reading one takes ms)


@dataclass
class Ears:
    """The app's lanes for recordings: one reader (and one for short recordings), each reading
    in a worker process (`readers`, the server process's own), and `TRANSCRIBERS`
    transcriptions at once (and one more for short recordings)."""

    readers: Readers
    reading: Lanes
    transcribing: Lanes

    @classmethod
    def open(cls, config: SpeechConfig) -> Ears:
        return cls(
            READERS,
            Lanes(
                "reader",
                "reading",
                workers=1,
                reserved=1,
                max_waiting=WAITING,
                max_wait=READ_SECONDS,
            ),
            Lanes(
                "transcriber",
                "the transcription server",
                workers=TRANSCRIBERS,
                reserved=RESERVED,
                max_waiting=WAITING,
                max_wait=config.timeout,
            ),
        )

    def close(self) -> None:
        self.reading.close()
        self.transcribing.close()


@router.get("/speech", tags=["speech"])
async def speech_settings(request: Request) -> dict[str, Any]:
    """Whether push-to-talk works here, and its limits (the page reads them first)."""
    config = ctx(request).agent.settings.speech
    why = speech_off(config)
    if not why:  # the page looks before its first recording: start the readers now
        ears: Ears = request.app.state.ears
        ears.readers.warm()
    return {
        "configured": not why,
        "why": why,
        "confirm": config.confirm,
        "max_seconds": config.max_seconds,
        "max_bytes": config.max_bytes,
        "types": ALLOWED,
    }


def _moving(web: WebContext) -> bool:
    """Whether the robot moves or is about to: a mission runs or waits, or its state says so
    (teleop, another interface's mission); a robot that cannot say is taken as moving."""
    if web.desk.running() is not None or web.desk.queued():
        return True
    try:
        return web.agent.robot.get_state().is_moving
    except RobotError:
        return True


def _answer(status: int, detail: str, **extra: Any) -> StrictJSON:
    if status == 422:  # the app's 422 shape: what was wrong, and where
        extra = {"problems": [{"where": "body", "problem": detail}], **extra}
    return StrictJSON({"detail": detail, **extra}, status_code=status)


def _doc(description: str) -> dict[str, Any]:
    return {"model": Problem, "description": description}


_SPEECH_ANSWERS: dict[int | str, dict[str, Any]] = {
    200: {
        "description": "a spoken stop (`estop: true`), or with speech.confirm the transcript "
        "to confirm (`confirm: true`)"
    },
    408: _doc("the recording did not arrive within speech.upload_timeout"),
    409: _doc("the e-stop is latched, or a person is driving"),
    413: _doc("the recording is over speech.max_bytes or speech.max_seconds"),
    415: _doc("not audio/webm, audio/ogg or audio/wav"),
    422: _doc("the recording cannot be read, or nothing was heard"),
    429: _doc("the queue is full, or newer recordings pushed this one out"),
    502: _doc("the transcription server answered an error (named, with its status)"),
    503: _doc(
        "no transcription server is configured, it does not answer, or the recording waited "
        "too long for it"
    ),
}


@router.post(
    "/speech",
    status_code=202,
    operation_id="post_speech",
    responses=_SPEECH_ANSWERS,
    tags=["speech"],
    openapi_extra={
        "requestBody": {
            "required": True,
            "content": {
                t: {"schema": {"type": "string", "format": "binary"}}
                for t in ("audio/webm", "audio/ogg", "audio/wav")
            },
        }
    },
)
async def speech(request: Request) -> StrictJSON:
    """A recording (the body; Content-Type audio/webm, audio/ogg or audio/wav) to a mission.

    202 with the transcript and the mission's id; 200 with `estop: true` for a spoken stop,
    or `confirm: true` when the person must confirm first; 413 when the recording is too long,
    415 for another type, 422 when nothing was heard, 503 without a transcription server.
    """
    web = ctx(request)
    config = web.agent.settings.speech
    why = speech_off(config)
    if why:
        return _answer(503, why)
    data = await request.body()  # whole already: the gate read it, within its time
    kind = request.headers.get("content-type", "")
    ears: Ears = request.app.state.ears
    if not taken(kind):  # said at once, without a reader
        return _answer(415, not_taken(kind))
    try:
        audio = await asyncio.wrap_future(
            ears.reading.submit(
                partial(ears.readers.inspect, data, kind, config.max_seconds),
                urgent=len(data) <= URGENT_BYTES,
            )
        )
        text = await asyncio.wrap_future(
            ears.transcribing.submit(
                partial(Transcriber(config).transcribe, data, audio),
                urgent=audio.seconds <= URGENT_SECONDS,
            )
        )
    except RecordingTooLong as exc:
        return _answer(413, str(exc))
    except AudioProblem as exc:
        return _answer(422, str(exc))
    except (TranscriptionError, HearingBusy) as exc:
        return _answer(exc.status, str(exc))
    if not text:
        return _answer(422, "nothing was heard in the recording: hold the button and speak")
    stop = is_stop(text)  # while the robot moves, a stop said first is a stop too
    rest = leading_stop(text) if not stop and _moving(web) else None
    if stop or rest is not None:
        dropped = web.desk.estop()  # the robot stops first, before anything is planned
        said = "e-stop latched: the robot is stopped; release it to run missions"
        extra = {} if rest is None else {"not_run": rest}
        if rest is not None:
            said += f" ({rest!r} was not run: say it again once released)"
        return StrictJSON(
            {"transcript": text, "estop": True, "dropped": dropped, **extra, "message": said}
        )
    problem = mission_text_problem(text, web.agent.settings.agent.max_mission_chars, "the text")
    if problem:
        return _answer(422, problem, transcript=text)
    if config.confirm:
        return StrictJSON({"transcript": text, "confirm": True, "mission_id": None})
    record, refused = web.desk.submit(text)
    if record is None:
        status = 409 if refused in (ESTOP_LATCHED, TELEOP_BUSY) else 429
        return _answer(status, f"Refused: {refused}.", transcript=text)
    return StrictJSON(
        {
            "transcript": text,
            "mission_id": record.id,
            "url": f"/api/missions/{record.id}",
            "message": "mission accepted",
        },
        status_code=202,
    )
