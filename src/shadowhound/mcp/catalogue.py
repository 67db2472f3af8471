"""The MCP tool list: names, short descriptions and input schemas, as plain dicts.

Skill tools come from the skill registry (one source of truth: the same names, descriptions
and schemas the LLM planner sends as function tools), except that a numeric argument is
declared as a number or a string: the registry reads text with a unit ("50 cm", "90°",
"2 min") as it reads a number, and a client that follows the schema must be able to send it.
The other tools are few and described in a line each, so the whole list costs a client's
model less than the planner's own prompt (bench/bench_mcp.py measures both).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from typing import Any

from ..errors import ToolInputError
from ..skills import Skill, SkillRegistry
from ..skills.arguments import is_numeric

_NO_ARGS: dict[str, Any] = {"type": "object", "properties": {}, "additionalProperties": False}


@dataclass(frozen=True)
class ToolSpec:
    """One MCP tool. `skill` names the registry skill a skill tool runs (else None)."""

    name: str
    description: str
    input_schema: dict[str, Any]
    skill: str | None = None
    read_only: bool = False

    def check_args(self, args: Any) -> None:
        """The schema's rules for a non-skill tool's arguments, each said in a sentence
        (skill tools are checked by the registry). Raises ToolInputError."""
        if not isinstance(args, dict):
            raise ToolInputError(f"{self.name}: arguments must be an object")
        props = self.input_schema.get("properties", {})
        unknown = sorted(set(args) - set(props))
        if unknown:
            raise ToolInputError(
                f"{self.name}: unknown argument(s) {', '.join(unknown)}; allowed: "
                + (", ".join(props) or "none")
            )
        for name in self.input_schema.get("required", []):
            if name not in args:
                raise ToolInputError(f"{self.name}: missing required argument {name!r}")
        for name, value in args.items():
            kind = props[name].get("type")
            ok = {
                "string": isinstance(value, str),
                "boolean": isinstance(value, bool),
                "integer": isinstance(value, int) and not isinstance(value, bool),
            }.get(kind, True)
            if not ok:
                raise ToolInputError(
                    f"{self.name}: {name!r} must be a {kind}, got "
                    f"{type(value).__name__} {str(value)[:40]!r}"
                )

    def to_dict(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "description": self.description,
            "inputSchema": self.input_schema,
        }


def _text_schema(limit: int, extra: dict[str, Any] | None = None) -> dict[str, Any]:
    props: dict[str, Any] = {
        "text": {
            "type": "string",
            "minLength": 1,
            "maxLength": limit,
            "description": "what the robot should do",
        }
    }
    props.update(extra or {})
    return {
        "type": "object",
        "properties": props,
        "required": ["text"],
        "additionalProperties": False,
    }


def mission_tools(max_mission_chars: int, *, release_estop: bool = False) -> list[ToolSpec]:
    """The tools that are not skills; `release_estop` only when the server offers it (each
    call asks the person)."""
    release = [
        ToolSpec(
            "release_estop",
            "Release a latched e-stop, only if the person agrees (asked through the client).",
            _NO_ARGS,
        )
    ]
    return [
        ToolSpec(
            "run_mission",
            "Plan a sentence into checked skills and run it on the robot.",
            _text_schema(max_mission_chars, {"dry_run": {"type": "boolean", "default": False}}),
        ),
        ToolSpec(
            "plan_mission",
            "Plan and check only (a dry run): steps, predicted path, refusals. Nothing moves.",
            _text_schema(max_mission_chars),
            read_only=True,
        ),
        ToolSpec(
            "get_state",
            "The robot's pose, posture, battery, e-stop and mission.",
            _NO_ARGS,
            read_only=True,
        ),
        ToolSpec("get_camera_image", "The latest camera image (JPEG).", _NO_ARGS, read_only=True),
        ToolSpec(
            "emergency_stop",
            "Stop the robot now; it stays stopped until a person releases the e-stop.",
            _NO_ARGS,
        ),
        *(release if release_estop else []),
        ToolSpec("cancel_mission", "Cancel the running mission; the robot stops.", _NO_ARGS),
        ToolSpec(
            "history",
            "Recent missions, newest first.",
            {
                "type": "object",
                "properties": {
                    "limit": {"type": "integer", "minimum": 1, "maximum": 100, "default": 10}
                },
                "additionalProperties": False,
            },
            read_only=True,
        ),
    ]


def skill_tools(registry: SkillRegistry) -> list[ToolSpec]:
    """One tool per skill, named like the planner's function tools (`nav_move`)."""
    return [ToolSpec(s.tool_name, s.description, skill_schema(s), skill=s.name) for s in registry]


def skill_schema(skill: Skill) -> dict[str, Any]:
    """The skill's argument schema, a numeric argument a number or a string: `"type":
    ["number", "string"]` (its bounds apply to numbers; text is read by shadowhound.units,
    which refuses a wrong unit, "3 s" for a length, with what is allowed)."""
    schema = skill.parameters_schema()
    for name, info in skill.args_model.model_fields.items():
        if is_numeric(info):
            prop = schema["properties"][info.alias or name]
            for branch in prop.get("anyOf", [prop]):  # an optional one: [number, null]
                if branch.get("type") in ("number", "integer"):
                    branch["type"] = [branch["type"], "string"]
    return schema


def all_tools(
    registry: SkillRegistry, max_mission_chars: int, *, release_estop: bool = False
) -> list[ToolSpec]:
    return mission_tools(max_mission_chars, release_estop=release_estop) + skill_tools(registry)


def list_size(tools: list[ToolSpec]) -> int:
    """Characters of the tools/list answer's tools, as compact JSON (what a client forwards)."""
    return len(json.dumps([t.to_dict() for t in tools], separators=(",", ":")))
