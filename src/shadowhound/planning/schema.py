"""The plan schema, generated from the skill registry in the dialect each server enforces.

A plan is `{"steps": [step, ...], "answer": "...", "conditions": [...]}`. It comes in two
styles (`llm.plan_schema`):

- `compact` (the default): a step is `{"skill": one of the skills' names, "args": {...}}`,
  `args` holding only arguments some skill takes, typed. About 1,700 characters, so prompt and
  schema fit 5,000 (issue 26); which skill takes which argument, the required ones and ranges
  are the registry's checks, and an invalid plan gets a repair turn saying what is allowed.
- `strict`: each step is one of the skills (`anyOf` over them), its name as a constant and
  an `args` object with exactly that skill's arguments (required ones required, types, enums,
  ranges where the dialect has them): a grammar cannot produce a wrong argument at all, which
  helps a small local model, at about four times the size.

Numbers are plain JSON numbers in the units the prompt names: a grammar that lets a model
write "3 cm" would also let it write "3 bananas".

A condition the request states ("until you see the red ball", "if the battery is below 30%")
is a `conditions` entry about one step: `{"step": n, "when": until | unless | if | if_not,
"kind": seen | in_the_way | battery_below | operator_stop, "name", "within", "percent"}`
(`parse.py` makes it the step's `plan.Watch` or guard; checking says whether the robot can
observe it).

One more choice stands beside the skills: the refusal, `{"skill": "refuse", "args": {"reason":
"..."}}`. A model that does not understand a request ("blorp the zanzibar") meets it where it
would otherwise pick a skill and invent motion; a plan with a refusal in it is refused as a
whole, with the model's reason (`parse.py`). It is a step in form only, so the schema keeps one
shape in every dialect (OpenAI's strict mode wants one object at the root, every property
required) and `refuse`, having no dot, can never be a skill's name.

Dialects (`dialect_of` picks one per backend):
- `openai`: OpenAI strict structured outputs (`strict: true`). Its subset wants every property
  required (an optional argument is `null`-able instead: in the compact style every argument
  is, and a null where the skill takes no null means "not given", `without_unset`), `enum`
  rather than `const`, and no string lengths; numeric ranges are allowed.
- `json_schema`: vLLM's structured outputs (`response_format` json_schema, enforced by its
  grammar backend) and Ollama (the OpenAI-compatible `response_format` becomes its `format`).
- `llamacpp`: llama-server and llama-cpp-python 0.3.x: `response_format` `json_object` with a
  `schema`, compiled to a GBNF grammar. Its converter handles `anyOf`, `const`, `enum`,
  `required`, `additionalProperties` and `minLength`; llama-cpp-python ignores numeric ranges
  (a TODO in its converter), so they are not sent, nor `maxLength`, which it unrolls into a
  grammar rule per character (a 35 kB grammar for this registry instead of a few kB). In the
  strict style an optional number with a range (speed, heading, laps) is not offered at all:
  the grammar could not keep it in range, and the skill's default is always valid. A required
  one (a distance) stays; the registry checks its range and the repair turn says what is
  allowed.

In the strict style, alternative argument sets (`oneOf` of `required`: nav.goto's x and y, or
a place) are steps of their own, so half a target is outside the schema; skills without
arguments share one step; an argument schema met more than once is written once in `$defs`.

The schema is a guarantee only where the server enforces it: every plan is still validated
against the registry, and an invalid one still gets a repair turn.

Everything here is cached per registry, dialect and style and built deterministically, so the
bytes sent are identical from mission to mission (servers cache compiled grammars by schema):
treat the returned dicts as read-only.
"""

from __future__ import annotations

import dataclasses
import functools
import json
from collections import Counter
from typing import Any, Literal

from ..plan import GUARD_WHEN, WATCH_KINDS, WATCH_WHEN, SkillCall
from ..skills import Skill, SkillRegistry
from .prompts import function_tool

Dialect = Literal["openai", "json_schema", "llamacpp"]
Style = Literal["compact", "strict"]

ANSWER_MAX_CHARS = 300  # a short reason when nothing can be done; also stops a model rambling
REFUSE = "refuse"  # the step that refuses the request instead of planning it

_RANGES = ("minimum", "maximum", "exclusiveMinimum", "exclusiveMaximum")
_LENGTHS = ("minLength", "maxLength")
# What each dialect keeps of a property's schema besides its type and enum.
_KEEP: dict[str, tuple[str, ...]] = {
    "openai": _RANGES,
    "json_schema": _RANGES + _LENGTHS,
    "llamacpp": ("minLength",),
}


def dialect_of(backend: str) -> Dialect:
    """The schema dialect the server behind `backend` enforces."""
    if backend == "openai":
        return "openai"
    if backend == "llamacpp":
        return "llamacpp"
    return "json_schema"


def args_schema(skill: Skill, dialect: Dialect) -> list[dict[str, Any]]:
    """The skill's arguments as closed object schemas in `dialect`: one per alternative set of
    arguments the skill accepts (nav.goto: x and y, or a place), else one."""
    return [_args_schema(skill, dialect, a) for a in _alternatives(skill)]


def _alternatives(skill: Skill) -> list[tuple[str, ...]]:
    """The argument sets a skill accepts one of (`oneOf` of `required` in its schema, e.g.
    nav.goto's x and y, or place); one empty set for a skill without alternatives."""
    alternatives = skill.parameters_schema().get("oneOf", [])
    return [tuple(a.get("required", [])) for a in alternatives] or [()]


@functools.lru_cache(maxsize=512)
def _args_schema(
    skill: Skill, dialect: Dialect, alternative: tuple[str, ...] = ()
) -> dict[str, Any]:
    full = skill.parameters_schema()
    required = list(full.get("required", [])) + list(alternative)
    others = {n for a in _alternatives(skill) for n in a} - set(alternative)
    props: dict[str, Any] = {}
    for name, prop in full.get("properties", {}).items():
        branches = [b for b in prop.get("anyOf", [prop]) if b.get("type") != "null"]
        nullable = len(branches) < len(prop.get("anyOf", [prop]))
        if name in others:
            continue  # it belongs to another alternative: "x" in the step that goes to a place
        if (
            dialect == "llamacpp"
            and name not in required
            and any(k in branches[0] for k in _RANGES)
        ):
            # The grammar cannot hold a number in its range, and the argument is optional:
            # not offered at all, so the skill's default applies (speed, heading, laps).
            continue
        base = {k: v for k, v in branches[0].items() if k in ("type", "enum", *_KEEP[dialect])}
        if dialect == "openai" and name not in required:
            # Strict mode: every property is required. An optional argument the skill accepts
            # as None may be null; one with another default (nav.patrol's laps) must be given.
            base = {"anyOf": [base, {"type": "null"}]} if nullable else base
        props[name] = base
    if dialect == "openai":
        required = list(props)
    schema: dict[str, Any] = {"type": "object", "properties": props}
    if required:
        schema["required"] = required
    schema["additionalProperties"] = False
    return schema


def _name(names: list[str], dialect: Dialect) -> dict[str, Any]:
    if dialect == "openai" or len(names) > 1:
        return {"type": "string", "enum": names}
    return {"type": "string", "const": names[0]}


def _step(names: list[str], args: dict[str, Any], dialect: Dialect) -> dict[str, Any]:
    return {
        "type": "object",
        "properties": {"skill": _name(names, dialect), "args": args},
        "required": ["skill", "args"],
        "additionalProperties": False,
    }


def _dump(value: Any) -> str:
    return json.dumps(value, separators=(",", ":"))


def _share(found: list[tuple[str, dict[str, Any]]], defs: dict[str, Any]) -> dict[str, str]:
    """Of the schemas `found` (each with a name to give it), those met more than once where a
    reference is shorter: each added to `defs` once. Returns {schema as JSON: its name}."""
    counts = Counter(_dump(schema) for _, schema in found)
    names: dict[str, str] = {}
    for hint, schema in found:
        text = _dump(schema)
        if text in names or counts[text] < 2:
            continue
        name = hint
        while name in defs:
            name += "_"
        cost = len(_dump({name: schema})) + 1  # its entry in $defs
        if counts[text] * (len(text) - len(_dump(_ref(name)))) <= cost:
            continue
        defs[name] = schema
        names[text] = name
    return names


def _ref(name: str) -> dict[str, str]:
    return {"$ref": f"#/$defs/{name}"}


def _steps(skills: tuple[Skill, ...], dialect: Dialect) -> tuple[list[Any], dict[str, Any]]:
    """The steps of a plan (skills without arguments sharing one) and their shared `$defs`."""
    shapes: list[tuple[list[str], dict[str, Any]]] = []
    bare: list[str] = []  # the skills without arguments: one step for them all
    for skill in skills:
        for args in args_schema(skill, dialect):
            if skill.parameters_schema().get("properties"):  # even if this dialect leaves all out
                shapes.append(([skill.name], args))
            elif not bare:
                bare.append(skill.name)
                shapes.append((bare, args))
            else:
                bare.append(skill.name)
    defs: dict[str, Any] = {}
    props = _share([p for _, a in shapes for p in a["properties"].items()], defs)
    shapes = [
        (names, {**a, "properties": {k: _shared(v, props) for k, v in a["properties"].items()}})
        for names, a in shapes
    ]
    whole = _share([(f"{next(iter(a['properties']), 'none')}_args", a) for _, a in shapes], defs)
    steps = [_step(names, _shared(a, whole), dialect) for names, a in shapes]
    return steps, defs


def _shared(schema: dict[str, Any], names: dict[str, str]) -> dict[str, Any]:
    name = names.get(_dump(schema))
    return schema if name is None else _ref(name)


def _refusal(dialect: Dialect) -> dict[str, Any]:
    """The refusal as a step: `refuse` with the model's reason, a short non-empty string."""
    reason: dict[str, Any] = {"type": "string"}
    if dialect != "openai":
        reason["minLength"] = 1
    if dialect == "json_schema":
        reason["maxLength"] = ANSWER_MAX_CHARS
    args = {
        "type": "object",
        "properties": {"reason": reason},
        "required": ["reason"],
        "additionalProperties": False,
    }
    return _step([REFUSE], args, dialect)


def _conditions(dialect: Dialect) -> dict[str, Any]:
    """The plan's conditions: each about one step (1-based), a watch ("until", "unless") or a
    guard ("if", "if_not" for an otherwise) of one kind (plan.Watch)."""
    step: dict[str, Any] = {"type": "integer"}
    if dialect != "llamacpp":
        step["minimum"] = 1
    props: dict[str, Any] = {
        "step": step,
        "when": {"type": "string", "enum": [*WATCH_WHEN, *GUARD_WHEN]},
        "kind": {"type": "string", "enum": list(WATCH_KINDS)},
        "name": {"type": "string"},
        "within": {"type": "number"},
        "percent": {"type": "number"},
    }
    required = ["step", "when", "kind"]
    if dialect == "openai":  # strict: every property required, the optional ones null-able
        for optional in ("name", "within", "percent"):
            props[optional] = {"type": [props[optional]["type"], "null"]}
        required = list(props)
    item = {
        "type": "object",
        "properties": props,
        "required": required,
        "additionalProperties": False,
    }
    return {"type": "array", "items": item}


def _shared_defs(conditions: dict[str, Any], defs: dict[str, Any]) -> dict[str, Any]:
    """The conditions' properties written as references to `defs` where one is the same."""
    named = {_dump(schema): name for name, schema in defs.items()}
    item = conditions["items"]
    props = {k: _shared(v, named) for k, v in item["properties"].items()}
    return {**conditions, "items": {**item, "properties": props}}


@functools.lru_cache(maxsize=64)
def _plan_schema(skills: tuple[Skill, ...], dialect: Dialect, style: Style) -> dict[str, Any]:
    defs: dict[str, Any] = {}
    if style == "compact":
        items = _compact_step(skills, dialect)
    else:
        steps, defs = _steps(skills, dialect)
        steps.append(_refusal(dialect))
        items = {"anyOf": steps}
    answer: dict[str, Any] = {"type": "string"}
    if dialect == "json_schema":
        answer["maxLength"] = ANSWER_MAX_CHARS
    plan: dict[str, Any] = {
        "type": "object",
        "properties": {
            "steps": {"type": "array", "items": items},
            "answer": answer,
            "conditions": _shared_defs(_conditions(dialect), defs),
        },
        "required": ["steps", "answer", "conditions"] if dialect == "openai" else ["steps"],
        "additionalProperties": False,
    }
    if defs:
        plan["$defs"] = defs
    return plan


_ANY = ["string", "number", "boolean"]  # an argument whose schema names no type


def _compact_step(skills: tuple[Skill, ...], dialect: Dialect) -> dict[str, Any]:
    """One step for every skill: the skill's name and any argument some skill takes, typed
    (the types an argument has in any skill; null-able and required in OpenAI's strict mode).
    Which arguments a skill takes, their ranges and enums (a trick) are the registry's checks
    (the prompt lists the tricks)."""
    found: dict[str, list[dict[str, Any]]] = {}
    for skill in skills:
        for name, prop in skill.parameters_schema().get("properties", {}).items():
            branches = [b for b in prop.get("anyOf", [prop]) if b.get("type") != "null"]
            found.setdefault(name, []).extend(branches)
    found.setdefault("reason", []).append({"type": "string"})  # the refusal's
    props: dict[str, Any] = {}
    for name, branches in found.items():
        types = list(dict.fromkeys(t for b in branches for t in _types(b))) or list(_ANY)
        if dialect == "openai":
            types.append("null")
        props[name] = {"type": types[0] if len(types) == 1 else types}
    args: dict[str, Any] = {"type": "object", "properties": props}
    if dialect == "openai":
        args["required"] = list(props)
    args["additionalProperties"] = False
    names = [s.name for s in skills] + [REFUSE]
    return _step(names, args, dialect)


def _types(branch: dict[str, Any]) -> list[str]:
    kind = branch.get("type")
    if kind is None and "enum" in branch:  # an enum of strings without a type
        kind = sorted({type(v).__name__.replace("str", "string") for v in branch["enum"]})
    if kind is None:
        return []
    return [kind] if isinstance(kind, str) else [k for k in kind if k != "null"]


def plan_schema(
    registry: SkillRegistry, dialect: Dialect = "json_schema", style: Style = "compact"
) -> dict[str, Any]:
    """The JSON Schema of a whole plan over `registry`'s skills, in `dialect` and `style`."""
    return _plan_schema(tuple(registry), dialect, style)


def response_format(
    backend: str, registry: SkillRegistry, style: Style = "compact"
) -> dict[str, Any]:
    """The `response_format` that constrains a reply to a plan on `backend`'s server."""
    dialect = dialect_of(backend)
    schema = plan_schema(registry, dialect, style)
    if dialect == "llamacpp":
        return {"type": "json_object", "schema": schema}
    spec: dict[str, Any] = {"name": "plan", "schema": schema}
    if dialect == "openai":
        spec["strict"] = True
    return {"type": "json_schema", "json_schema": spec}


def without_unset(registry: SkillRegistry, call: SkillCall) -> SkillCall:
    """`call` without the arguments a model set to null where the skill takes no null: in
    OpenAI's strict mode every argument of the compact step is written, null meaning "not
    given" (another skill's argument, or this skill's default). A null the skill takes (a
    patrol's laps: until stopped) stays."""
    skill = registry.find(call.skill) if isinstance(call.skill, str) else None
    if skill is None or not isinstance(call.args, dict):
        return call
    own = skill.parameters_schema().get("properties", {})
    kept = {
        k: v
        for k, v in call.args.items()
        if v is not None or any(b.get("type") == "null" for b in own.get(k, {}).get("anyOf", []))
    }
    if len(kept) == len(call.args):
        return call
    return dataclasses.replace(call, args=kept)


def _strict_parameters(skill: Skill) -> dict[str, Any]:
    """One strict object for a tool: OpenAI wants an object at the root of `parameters`, so a
    skill with alternatives (nav.goto) gets all their arguments, null-able; the registry checks
    which combination was given."""
    alternatives = _alternatives(skill)
    if len(alternatives) == 1:
        return _args_schema(skill, "openai")
    merged: dict[str, Any] = {}
    for alternative in alternatives:
        for name, prop in _args_schema(skill, "openai", alternative)["properties"].items():
            merged.setdefault(
                name, prop if name not in alternative else {"anyOf": [prop, {"type": "null"}]}
            )
    return {
        "type": "object",
        "properties": merged,
        "required": list(merged),
        "additionalProperties": False,
    }


def strict_tools(registry: SkillRegistry) -> list[dict[str, Any]]:
    """The skills as OpenAI function tools with `strict: true` argument schemas."""
    return [function_tool(s, _strict_parameters(s), strict=True) for s in registry]
