"""The model planner's prompts, generated from the skill registry: compact, so small models
plan well.

Plan mode sends one system prompt listing every skill on one line each, and asks for a JSON
plan (constrained by `schema`'s plan schema where the server enforces one). Tool mode and
react mode send the skills as function tools with schemas stripped to what a model needs.
"""

from __future__ import annotations

import functools
import math
from typing import Any

from ..skills import Skill, SkillRegistry
from ..state import RobotState

_INTRO = (
    "You plan actions for ShadowHound, a Unitree Go2 quadruped robot. Units: metres, seconds, "
    "degrees, m/s. x is forward, y is left; positive angles turn left."
)
_RULES = (
    "Rules: only the skills listed; one step per action, in the order asked ('twice': two "
    "steps); numbers as numbers; to come back, nav.goto place 'start'; to go to, find or look "
    "for a thing, nav.goto with its name as place (seen or not)."
)
# What a condition's `when` and `kind` may be, said once for both plan replies.
_CONDITION_KINDS = (
    "(when: until, unless, if, if_not for otherwise; kind: seen (name, within m), in_the_way "
    "(within m), battery_below (percent), operator_stop); never leave one out: refuse instead."
)
_PLAN_REPLY = (
    'Reply with JSON only: {"steps":[{"skill":"nav.move","args":{"distance":1}}],"answer":""}. '
    'A request no skill fits: the one step {"skill":"refuse","args":{"reason":"why"}}. Every '
    'condition stated goes in "conditions":[{"step":1,"when":"until","kind":"seen","name":'
    '"red ball"}] ' + _CONDITION_KINDS
)
# The same when the model is shown the plan's schema (OpenAI's strict structured outputs): the
# shape of the JSON is said there, not twice.
_SCHEMA_REPLY = (
    "Reply with the plan in its schema. A request no skill fits: the one step refuse, with a "
    "reason. Every condition stated goes in conditions, about its step " + _CONDITION_KINDS
)
_TOOLS_REPLY = (
    "Call the skills as tools, all of them at once, in order. A request no skill fits gets no "
    "call and a short reason."
)
_REACT_REPLY = (
    "Call one skill at a time and read its result before the next. If you cannot call tools, "
    'reply with JSON only: {"skill": "nav.move", "args": {"distance": 1.0}}. When the '
    "request is done, reply with a short answer for the user and no skill call; a request no "
    "skill fits gets no call and a short reason."
)


@functools.lru_cache(maxsize=256)
def compact_schema(skill: Skill) -> dict[str, Any]:
    """The skill's JSON Schema without titles and `null` branches (optional = not required).

    Cached (schema generation is the costliest part of a request): treat it as read-only.
    """
    full = skill.parameters_schema()
    props: dict[str, Any] = {}
    for name, prop in full.get("properties", {}).items():
        branches = [b for b in prop.get("anyOf", [prop]) if b.get("type") != "null"]
        slim = {k: v for k, v in branches[0].items() if k not in ("title", "default")}
        if prop.get("description"):
            slim["description"] = prop["description"]
        props[name] = slim
    schema: dict[str, Any] = {"type": "object", "properties": props}
    if full.get("required"):
        schema["required"] = full["required"]
    return schema


@functools.lru_cache(maxsize=256)
def skill_line(skill: Skill) -> str:
    """`nav.move(distance, speed?) - Walk straight ...`: the arguments by name (? optional,
    the values of an enum) and the description, which says what they mean: each thing said
    once, as the request is sent with every mission."""
    schema = compact_schema(skill)
    required = set(schema.get("required", []))
    params = []
    for name, prop in schema["properties"].items():
        enum = f": {'|'.join(map(str, prop['enum']))}" if "enum" in prop else ""
        params.append(f"{name}{'' if name in required else '?'}{enum}")
    return f"{skill.name}({', '.join(params)}) - {skill.description}"


def tools(registry: SkillRegistry) -> list[dict[str, Any]]:
    return [function_tool(s, compact_schema(s)) for s in registry]


def function_tool(
    skill: Skill,
    parameters: dict[str, Any],
    strict: bool = False,
) -> dict[str, Any]:
    """One skill as an OpenAI-style function tool (`strict` only where the API takes it)."""
    function: dict[str, Any] = {
        "name": skill.tool_name,
        "description": skill.description,
        "parameters": parameters,
    }
    if strict:
        function["strict"] = True
    return {"type": "function", "function": function}


def state_line(state: RobotState | None) -> str:
    if state is None:
        return ""
    return (
        f"Robot now: {state.posture.value} at x={state.x:.2f} y={state.y:.2f}, facing "
        f"{math.degrees(state.yaw):.0f} degrees, battery {state.battery_text}."
    )


def places_line(places: dict[str, tuple[float, float]]) -> str:
    named = ", ".join(f"{n} ({x:g}, {y:g})" for n, (x, y) in places.items())
    return f"Places: {named + ', ' if named else ''}start (where this mission began), home (0, 0)."


def objects_line(objects: dict[str, tuple[float, float]]) -> str:
    """The objects the robot has seen, where (a thing not listed can still be looked for)."""
    if not objects:
        return "Objects seen: none yet."
    return (
        "Objects seen: "
        + ", ".join(f"{n} ({x:.1f}, {y:.1f})" for n, (x, y) in objects.items())
        + "."
    )


def history_lines(history: list[str], limit: int) -> str:
    if not history or limit <= 0:
        return ""
    recent = [h if len(h) <= 200 else h[:197] + "..." for h in history[-limit:]]
    return "Recent missions:\n" + "\n".join(f"- {h}" for h in recent)


def memory_lines(memories: list[str]) -> str:
    return ("Relevant memories:\n" + "\n".join(f"- {m}" for m in memories)) if memories else ""


@functools.lru_cache(maxsize=64)
def _stable_prefix(skills: tuple[Skill, ...], style: str) -> str:
    parts = [_INTRO]
    # React also lists the skills: some servers drop `tools` (llama-cpp-python's default chat
    # format does), and the model must still know what it may call.
    if style in ("plan", "plan_schema", "react"):
        parts.append("Skills:\n" + "\n".join(skill_line(s) for s in skills))
    parts.append(_RULES)
    replies = {
        "plan": _PLAN_REPLY,
        "plan_schema": _SCHEMA_REPLY,
        "tools": _TOOLS_REPLY,
        "react": _REACT_REPLY,
    }
    parts.append(replies[style])
    return "\n".join(parts)


def stable_prefix(registry: SkillRegistry, *, style: str) -> str:
    """What every mission's system message starts with, byte for byte, for one registry and
    style: the intro, the skills, the rules and the reply format. Servers that cache prompts
    (llama.cpp's `cache_prompt`, OpenAI's and vLLM's prefix caching) evaluate it once."""
    return _stable_prefix(tuple(registry), style)


def system_prompt(
    registry: SkillRegistry,
    *,
    style: str,
    state: RobotState | None = None,
    places: dict[str, tuple[float, float]] | None = None,
    history: list[str] | None = None,
    history_size: int = 0,
    memories: list[str] | None = None,
    objects: dict[str, tuple[float, float]] | None = None,
) -> str:
    """The system message. `style` is plan (skills listed, JSON reply), plan_schema (the same,
    the model shown the plan's schema), tools or react.

    The stable prefix comes first; what changes from mission to mission (places, objects
    seen, recent missions, memories, the robot's state) comes last, so only that tail is
    evaluated anew.
    """
    parts = [
        stable_prefix(registry, style=style),
        places_line(places or {}),
        objects_line(objects or {}),
        history_lines(history or [], history_size),
        memory_lines(memories or []),
        state_line(state),
    ]
    return "\n".join(p for p in parts if p)
