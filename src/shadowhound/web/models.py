"""Request and answer bodies of the HTTP API (they also make the OpenAPI document)."""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel, ConfigDict, Field

# Hard ceiling for text fields; the agent's own limit (agent.max_mission_chars) is checked in
# the route so the answer can name it.
MAX_TEXT = 16_000


class MissionRequest(BaseModel):
    """`{"command": ...}` as in the original ShadowHound, plus `dry_run`."""

    model_config = ConfigDict(extra="forbid")

    command: str = Field(..., min_length=1, max_length=MAX_TEXT,
                         description="what the robot should do, e.g. 'walk forward 1 meter'")
    dry_run: bool = Field(False, description="plan and check only; nothing moves")
    priority: int | None = Field(0, ge=0, le=10,
                          description="accepted for compatibility with the original API; "
                                      "missions run in the order they arrive")


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
    model_config = ConfigDict(extra="forbid")

    text: str = Field(..., min_length=1, max_length=MAX_TEXT, description="a question")


class ChatAnswer(BaseModel):
    question: str
    answer: str


class RejectRequest(BaseModel):
    model_config = ConfigDict(extra="forbid")

    reason: str = Field("", max_length=500)


class EstopAnswer(BaseModel):
    estop: bool
    message: str
    dropped: int = 0
    robot: dict[str, Any] | None = None


class Problem(BaseModel):
    """Every 4xx answer: `detail` says what was wrong and what is allowed."""

    detail: Any
