"""Push-to-talk: `POST /api/speech` takes a recording, has it transcribed and runs what was
said as a mission (or, when the words are only "stop", "halt" or "e-stop", latches the e-stop
at once, before any planning). `GET /api/speech` tells the page whether it is set up.

The recording's size is limited by the gate (`speech.max_bytes`) and its length here, read
from the container (`speech.max_seconds`); it is sent to the configured server and never
kept. The transcript is the mission's command, stored only where missions are (the history,
when it is on). With `speech.confirm` the transcript comes back to be confirmed by a person
and nothing runs.
"""

from __future__ import annotations

import asyncio
from typing import Any

from fastapi import APIRouter, Request

from ..admission import ESTOP_LATCHED, mission_text_problem
from ..hearing import (
    ALLOWED,
    AudioProblem,
    Transcriber,
    TranscriptionError,
    inspect,
    is_stop,
    taken,
)
from ..hearing import not_configured as speech_off
from ..worker import TELEOP_BUSY
from .api import ctx
from .models import Problem
from .responses import StrictJSON

PATH = "/api/speech"
router = APIRouter(prefix="/api")


@router.get("/speech", tags=["speech"])
async def speech_settings(request: Request) -> dict[str, Any]:
    """Whether push-to-talk works here, and its limits (the page reads them first)."""
    config = ctx(request).agent.settings.speech
    why = speech_off(config)
    return {
        "configured": not why,
        "why": why,
        "confirm": config.confirm,
        "max_seconds": config.max_seconds,
        "max_bytes": config.max_bytes,
        "types": ALLOWED,
    }


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
    409: _doc("the e-stop is latched, or a person is driving"),
    413: _doc("the recording is over speech.max_bytes or speech.max_seconds"),
    415: _doc("not audio/webm, audio/ogg or audio/wav"),
    422: _doc("the recording cannot be read, or nothing was heard"),
    429: _doc("the queue is full"),
    502: _doc("the transcription server answered an error (named, with its status)"),
    503: _doc("no transcription server is configured, or it does not answer"),
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
    data = await request.body()
    kind = request.headers.get("content-type", "")
    try:
        audio = inspect(data, kind)
    except AudioProblem as exc:
        return _answer(422 if taken(kind) else 415, str(exc))
    if audio.seconds > config.max_seconds:
        return _answer(
            413,
            f"the recording is {audio.seconds:.0f} s long; at most {config.max_seconds:g} s "
            "are taken (speech.max_seconds): hold the button for one short request",
        )
    try:
        text = await asyncio.to_thread(Transcriber(config).transcribe, data, audio)
    except TranscriptionError as exc:
        return _answer(exc.status, str(exc))
    if not text:
        return _answer(422, "nothing was heard in the recording: hold the button and speak")
    if is_stop(text):
        dropped = web.desk.estop()  # the robot stops first, before anything is planned
        return StrictJSON(
            {
                "transcript": text,
                "estop": True,
                "dropped": dropped,
                "message": "e-stop latched: the robot is stopped; release it to run missions",
            }
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
