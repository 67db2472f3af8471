"""Questions for the person at the MCP client (elicitation): approving a risky call, releasing
the e-stop.

Over a connection with a back-channel (handshake-era stdio and HTTP sessions) the question goes
out at once (`ask_now`: `elicitation/create`). Without one (protocol 2026-07-28) the call
answers `InputRequiredResult` (`Questions.ask_later`), and the client calls again with the
person's answer, which `Questions.take` finds by the call's `request_state`. A client that does
not declare elicitation cannot ask anyone (`can_ask`): what needs a person is then refused.
"""

from __future__ import annotations

import asyncio
import secrets
from typing import Any, Generic, Protocol, TypeVar

import mcp_types as types
from mcp.server import ServerRequestContext

APPROVE_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "approve": {"type": "boolean", "title": "Approve", "description": "let the robot do this"}
    },
    "required": ["approve"],
}
RELEASE_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "release": {
            "type": "boolean",
            "title": "Release the e-stop",
            "description": "the robot may move again when missions are run",
        }
    },
    "required": ["release"],
}
ANSWER_KEY = "approval"  # the one input request of an InputRequiredResult


class Waiting(Protocol):
    """Something that waits for the person's answer, until it no longer does."""

    def pending(self) -> bool: ...


W = TypeVar("W", bound=Waiting)


def can_ask(ctx: ServerRequestContext[Any]) -> bool:
    """Whether the client declared that it can ask its person (elicitation)."""
    caps = ctx.session.client_capabilities
    return caps is not None and caps.elicitation is not None


def can_ask_now(ctx: ServerRequestContext[Any]) -> bool:
    """Whether this call has a back-channel for `ask_now` (else `Questions.ask_later`)."""
    return ctx.session.can_send_request


async def ask_now(
    ctx: ServerRequestContext[Any], message: str, schema: dict[str, Any], timeout: float
) -> types.ElicitResult:
    """The person's answer. Raises MCPError (the client could not ask) or TimeoutError."""
    return await asyncio.wait_for(
        ctx.session.elicit_form(message, schema, related_request_id=ctx.request_id),
        timeout=timeout,
    )


def said_yes(answer: Any, field: str) -> bool:
    """Whether `answer` accepted the form with `field` set to true."""
    return (
        isinstance(answer, types.ElicitResult)
        and answer.action == "accept"
        and (answer.content or {}).get(field) is True
    )


class Questions(Generic[W]):
    """Questions asked by `InputRequiredResult`, each waiting for the call with its answer."""

    def __init__(self) -> None:
        self._waiting: dict[str, W] = {}  # request_state -> what waits for the answer

    def ask_later(
        self, waiting: W, message: str, schema: dict[str, Any]
    ) -> types.InputRequiredResult:
        state = secrets.token_urlsafe(16)
        self._waiting = {k: w for k, w in self._waiting.items() if w.pending()}
        self._waiting[state] = waiting
        return types.InputRequiredResult(
            input_requests={
                ANSWER_KEY: types.ElicitRequest(
                    params=types.ElicitRequestFormParams(message=message, requested_schema=schema)
                )
            },
            request_state=state,
        )

    def take(self, params: types.CallToolRequestParams) -> tuple[W, Any] | None:
        """What still waits for this call's answer, and the answer (None if it sent none)."""
        waiting = self._waiting.pop(params.request_state or "", None)
        if waiting is None or not waiting.pending():
            return None
        return waiting, (params.input_responses or {}).get(ANSWER_KEY)
