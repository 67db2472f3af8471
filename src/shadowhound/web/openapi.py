"""The OpenAPI document says what the server really sends.

FastAPI documents each route's own answers. Two kinds of answers come from elsewhere; they are
added here from the same settings that produce them:

- 422 comes from the app's validation handler (`detail` text and a `problems` list, see
  `ValidationProblem`), not FastAPI's default shape. Routes that validate nothing have none.
- The gate (security.py) answers before any route: 400 for a Host that is not allowed (only
  when it checks hosts), 401 without a valid token (only when the server has one), 403 for a
  cross-origin request that would change something and 413 for a body over the limit (both only
  on methods that change things).
"""

from __future__ import annotations

from typing import Any

from pydantic import BaseModel

from .models import MAX_TEXT, Problem, ValidationProblem
from .security import OPEN_PATHS, SAFE_METHODS

_REF = "#/components/schemas/{model}"
_FASTAPI_422 = ("HTTPValidationError", "ValidationError")


def document_answers(
    schema: dict[str, Any], *, token: bool, checks_hosts: bool, max_body: int
) -> dict[str, Any]:
    """Add the gate's answers and the real 422 to `schema` (FastAPI's document), in place."""
    gate = {
        400: (
            checks_hosts and not token,
            "the Host header is not a loopback name (without a "
            "token the server answers only on loopback), or is "
            "not a valid host[:port]",
        ),
        401: (token, "a valid token is required: 'Authorization: Bearer <token>'"),
        403: (True, "a cross-origin request: only the dashboard's own page may change things"),
        413: (
            True,
            f"the request body is larger than {max_body} bytes (text fields have their "
            f"own limit of {MAX_TEXT} characters: 422)",
        ),
    }
    for path, operations in schema.get("paths", {}).items():
        for method, operation in operations.items():
            answers = operation.setdefault("responses", {})
            if "422" in answers:
                answers["422"] = _answer(
                    ValidationProblem,
                    "the request does not match the schema, or a text is over the agent's limit",
                )
            changes = method.upper() not in SAFE_METHODS
            for code, (applies, description) in gate.items():
                if code == 401 and (path in OPEN_PATHS or not path.startswith("/api/")):
                    continue
                if code in (403, 413) and not changes:
                    continue
                if applies:
                    answers[str(code)] = _answer(Problem, description)
    components = schema.setdefault("components", {}).setdefault("schemas", {})
    for model in (Problem, ValidationProblem):
        found = model.model_json_schema(ref_template=_REF)
        components.update(found.pop("$defs", {}))
        components[model.__name__] = found
    _drop_unused(schema, _FASTAPI_422)
    return schema


def _answer(model: type[BaseModel], description: str) -> dict[str, Any]:
    schema = {"$ref": _REF.format(model=model.__name__)}
    return {"description": description, "content": {"application/json": {"schema": schema}}}


def _drop_unused(schema: dict[str, Any], names: tuple[str, ...]) -> None:
    """Remove the components `names` once nothing refers to them (FastAPI's 422 models)."""
    components = schema.get("components", {}).get("schemas", {})
    for name in names:  # in order: a model that refers to a later one goes first
        rest = {
            **schema,
            "components": {
                **schema.get("components", {}),
                "schemas": {k: v for k, v in components.items() if k != name},
            },
        }
        if _REF.format(model=name) not in _refs(rest):
            components.pop(name, None)


def _refs(node: Any) -> set[str]:
    """Every `$ref` value in a JSON document."""
    if isinstance(node, dict):
        found = {node["$ref"]} if isinstance(node.get("$ref"), str) else set()
        return found.union(*(_refs(v) for v in node.values()))
    if isinstance(node, list):
        return set().union(*(_refs(v) for v in node))
    return set()
