"""Request and answer bodies of the HTTP API (they also make the OpenAPI document).

Request bodies are strict: a JSON string is not a boolean (`"dry_run": "yes"` is refused) and a
boolean is not a number, so what a client sends is what the robot gets, or a 422 naming the
field. The error bodies are here too (openapi.py puts them in the document).
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field, model_validator

# Hard ceiling for text fields; the agent's own limit (agent.max_mission_chars) is checked in
# the route so the answer can name it.
MAX_TEXT = 16_000
# The body limit (413) lets through every body whose text fields keep to MAX_TEXT however a
# client encodes them: JSON may spell one character as 12 bytes (an escaped surrogate pair).
MAX_BODY = 12 * MAX_TEXT + 4096

_STRICT = ConfigDict(extra="forbid", strict=True)
MAX_SEQ = 2**53 - 1  # the largest whole number a page's JavaScript counts exactly


class MissionRequest(BaseModel):
    """`{"command": ...}` as in the original ShadowHound, plus `dry_run`."""

    model_config = ConfigDict(
        **_STRICT,
        json_schema_extra={
            "examples": [
                {"command": "walk forward 1 meter then turn left 90 degrees"},
                {"command": "go to x 2 y 1", "dry_run": True},
            ]
        },
    )

    command: str = Field(
        ...,
        min_length=1,
        max_length=MAX_TEXT,
        description="what the robot should do, e.g. 'walk forward 1 meter'",
    )
    dry_run: bool = Field(False, description="plan and check only; nothing moves")
    priority: int | None = Field(
        0,
        ge=0,
        le=10,
        description="accepted for compatibility with the original API; "
        "missions run in the order they arrive",
    )


class MissionAccepted(BaseModel):
    """The 202 answer. `success`, `message` and `command` are the original answer's keys."""

    success: bool
    message: str
    command: str
    mission_id: str
    state: str
    dry_run: bool
    queued_ahead: int
    url: str


class ChatRequest(BaseModel):
    model_config = ConfigDict(
        **_STRICT, json_schema_extra={"examples": [{"text": "where are you?"}]}
    )

    text: str = Field(..., min_length=1, max_length=MAX_TEXT, description="a question")


class ChatAnswer(BaseModel):
    question: str
    answer: str


class RejectRequest(BaseModel):
    model_config = _STRICT

    reason: str = Field("", max_length=500)


class EstopAnswer(BaseModel):
    estop: bool
    message: str
    dropped: int = 0
    robot: dict[str, Any] | None = None


class Problem(BaseModel):
    """An error answer: `detail` says what was wrong and what is allowed."""

    detail: str


class FieldProblem(BaseModel):
    where: str = Field(description="the field, e.g. 'body.dry_run' or 'query.limit'")
    problem: str


class ValidationProblem(BaseModel):
    """422: the request does not match the schema (`problems` names each field), or its text is
    over the agent's own limit (`agent.max_mission_chars`; then `problems` may be empty)."""

    detail: str
    problems: list[FieldProblem] = Field(default_factory=list)


class MissionRefused(BaseModel):
    """409 (the e-stop is latched) or 429 (the queue is full): the mission was not queued."""

    detail: str
    success: bool
    message: str
    command: str


class TeleopSwitch(BaseModel):
    """`{"on": true}` switches driving on (refused during a mission or a latched e-stop)."""

    model_config = _STRICT

    on: bool = Field(..., description="true: the pad drives the robot; false: it stops")


class TeleopDrive(BaseModel):
    """The pad's deflection, each from -1 (full back, right, clockwise) to 1. Sent about ten
    times a second while held: a deflection older than 0.35 s counts as zero (dead-man).
    `seq` grows with every request a page sends (the page takes its clock in milliseconds); one
    not above the last taken arrived late and is dropped."""

    model_config = ConfigDict(
        **_STRICT,
        json_schema_extra={
            "examples": [{"seq": 1732612345678, "forward": 0.5, "left": 0.0, "turn": -0.2}]
        },
    )

    seq: int = Field(
        ...,
        ge=1,
        le=MAX_SEQ,
        description="required: a number above the page's previous request's (its clock, ms)",
    )
    forward: float = Field(0.0, ge=-1, le=1, allow_inf_nan=False)
    left: float = Field(0.0, ge=-1, le=1, allow_inf_nan=False)
    turn: float = Field(0.0, ge=-1, le=1, allow_inf_nan=False)

    @model_validator(mode="before")
    @classmethod
    def _numbered(cls, data: Any) -> Any:
        if isinstance(data, dict) and "seq" not in data:
            raise ValueError(
                "seq is required: a whole number above the previous request's (a late request "
                "is dropped by it); a page without it is older than the server: reload it"
            )
        return data
