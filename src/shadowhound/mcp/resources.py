"""The MCP server's resources and its prompt: what a client may read about the robot, and a
template that has a model check a plan before it runs it."""

from __future__ import annotations

from collections.abc import Callable, Mapping
from typing import Any

import mcp_types as types
from mcp.shared.exceptions import MCPError

from .. import jsonout
from .desk import McpDesk

RESOURCES = {
    "shadowhound://skills": ("skills", "The skill catalogue with argument schemas."),
    "shadowhound://places": ("places", "Known places (profile and taught), odom frame."),
    "shadowhound://missions/last": ("last-mission", "The last mission's full record."),
}
MISSION_PROMPT = "mission"


def resource_list() -> types.ListResourcesResult:
    return types.ListResourcesResult(
        resources=[
            types.Resource(uri=uri, name=name, description=text, mime_type="application/json")
            for uri, (name, text) in RESOURCES.items()
        ]
    )


def read_resource(desk: McpDesk, uri: str) -> types.ReadResourceResult:
    """One resource as JSON (blocking: the server calls it on a thread)."""
    readers: dict[str, Callable[[], Any]] = {
        "shadowhound://skills": desk.agent.get_available_skills,
        "shadowhound://places": desk.places,
        "shadowhound://missions/last": desk.last_mission,
    }
    if uri not in readers:
        raise MCPError(
            types.INVALID_PARAMS,
            f"unknown resource {uri[:200]!r}; known: " + ", ".join(RESOURCES),
        )
    text = jsonout.dumps(readers[uri]())
    return types.ReadResourceResult(
        contents=[types.TextResourceContents(uri=uri, mime_type="application/json", text=text)]
    )


def prompt_list() -> types.ListPromptsResult:
    return types.ListPromptsResult(
        prompts=[
            types.Prompt(
                name=MISSION_PROMPT,
                description="Ask the robot to do something, checked first.",
                arguments=[
                    types.PromptArgument(
                        name="task", required=True, description="what the robot should do"
                    )
                ],
            )
        ]
    )


def get_prompt(name: str, arguments: Mapping[str, str] | None) -> types.GetPromptResult:
    if name != MISSION_PROMPT:
        raise MCPError(types.INVALID_PARAMS, f"unknown prompt {name!r}; known: {MISSION_PROMPT}")
    task = (arguments or {}).get("task", "").strip()
    if not task:
        raise MCPError(types.INVALID_PARAMS, "the mission prompt needs a 'task'")
    text = (
        f"Have the robot do this: {task}\n"
        "First call plan_mission with that sentence and read the plan and any refusals. "
        "If the plan is right, call run_mission with the same sentence and report what "
        "happened from its result. If anything looks unsafe, call emergency_stop."
    )
    return types.GetPromptResult(
        messages=[
            types.PromptMessage(role="user", content=types.TextContent(type="text", text=text))
        ]
    )
