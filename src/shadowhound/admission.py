"""What a mission must be before anything plans it: text within the limits, the e-stop released.

The agent refuses such missions itself; the interfaces that answer before a mission is queued
(the web API's 422/409, the MCP tools' errors) check the same rules with the same words, from
here, so a limit or a message is changed in one place.
"""

from __future__ import annotations

ESTOP_LATCHED = "the e-stop is latched; a person must release it before missions run"
EXAMPLE = "'walk forward 1 meter'"


def mission_text_problem(text: object, limit: int, what: str = "the mission") -> str | None:
    """Why `text` cannot be a mission, or None when it can.

    A mission is a string with something besides whitespace, at most `limit` characters long
    (`agent.max_mission_chars`). `what` names the text as the caller's users know it ("the
    command" on the web API, "text" for an MCP tool).
    """
    if not isinstance(text, str):
        return f"{what} must be a string, got {type(text).__name__}"
    if not text.strip():
        return f"{what} is empty; say what the robot should do, e.g. {EXAMPLE}"
    if len(text) > limit:
        return (
            f"{what} is {len(text)} characters long; the limit is {limit} (agent.max_mission_chars)"
        )
    return None
