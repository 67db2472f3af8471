"""The skill registry: the one source of truth for what the robot can be asked to do.

Each skill has typed arguments (a pydantic model), a description, a timeout on the robot's
clock, and a prediction of where it takes the robot (used by the safety check before a plan
runs). The CLI listing, the web page, language-model tool schemas and the offline planner all
read this registry.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any

from pydantic import ValidationError

from ..errors import SkillValidationError
from ..plan import SkillCall
from ..units import UnitError
from .arguments import SkillArgs

if TYPE_CHECKING:
    from ..state import Pose2D
    from .context import PlanEnv, SkillContext


Runner = Callable[["SkillContext", Any], str]
Predictor = Callable[["Pose2D", Any, "PlanEnv"], list["Pose2D"]]
Timeout = Callable[[Any, "PlanEnv"], float]


@dataclass(frozen=True)
class Skill:
    """A robot capability. `run` returns a short sentence saying what happened."""

    name: str
    description: str
    args_model: type[SkillArgs]
    run: Runner
    timeout: float | Timeout = 30.0  # seconds on the robot's clock
    moves: bool = False  # may translate or rotate the robot
    predict: Predictor | None = None  # poses the robot passes through, for the safety check

    @property
    def tool_name(self) -> str:
        """Name usable as an OpenAI function name (no dots allowed there)."""
        return self.name.replace(".", "_")

    def parameters_schema(self) -> dict[str, Any]:
        schema = self.args_model.model_json_schema()
        schema.pop("title", None)
        schema.pop("description", None)
        for prop in schema.get("properties", {}).values():
            prop.pop("title", None)
        schema.setdefault("properties", {})
        schema["additionalProperties"] = False
        return schema

    def timeout_for(self, args: SkillArgs, env: PlanEnv) -> float:
        return self.timeout(args, env) if callable(self.timeout) else float(self.timeout)

    def describe(self) -> dict[str, Any]:
        return {
            "name": self.name,
            "description": self.description,
            "parameters": self.parameters_schema(),
            "moves": self.moves,
            "timeout": None if callable(self.timeout) else self.timeout,
        }


@dataclass(frozen=True)
class ValidatedCall:
    """A skill call whose arguments passed the schema. Safety limits are checked separately."""

    skill: Skill
    args: SkillArgs
    label: str = ""

    @property
    def name(self) -> str:
        return self.skill.name

    def args_dict(self) -> dict[str, Any]:
        return self.args.model_dump(exclude_none=True)


class SkillRegistry:
    """Named skills. `validate` turns a SkillCall into a ValidatedCall or explains why not."""

    def __init__(self, skills: Iterable[Skill] = ()) -> None:
        self._skills: dict[str, Skill] = {}
        for skill in skills:
            self.register(skill)

    def register(self, skill: Skill) -> None:
        if skill.name in self._skills:
            raise ValueError(f"skill {skill.name!r} is already registered")
        if skill.name.count(".") != 1:
            raise ValueError(f"skill name {skill.name!r} must be namespaced as area.verb")
        self._skills[skill.name] = skill

    def __contains__(self, name: object) -> bool:
        return name in self._skills

    def __iter__(self):  # type: ignore[no-untyped-def]
        return iter(self._skills.values())

    def __len__(self) -> int:
        return len(self._skills)

    @property
    def names(self) -> list[str]:
        return list(self._skills)

    def get(self, name: str) -> Skill:
        skill = self._skills.get(name) or self._by_tool_name(name)
        if skill is None:
            raise SkillValidationError(
                [f"unknown skill {name!r}; available skills: {', '.join(self._skills)}"]
            )
        return skill

    def _by_tool_name(self, name: str) -> Skill | None:
        return next((s for s in self._skills.values() if s.tool_name == name), None)

    def validate(self, call: SkillCall) -> ValidatedCall:
        if not isinstance(call.skill, str) or not call.skill.strip():
            raise SkillValidationError([f"a step needs a skill name, got {call.skill!r}"])
        skill = self.get(call.skill.strip())
        args = call.args
        if args is None:
            args = {}
        if not isinstance(args, Mapping):
            raise SkillValidationError(
                [f"{skill.name}: arguments must be an object, got {type(args).__name__}"]
            )
        try:
            parsed = skill.args_model.model_validate(dict(args))
        except ValidationError as exc:
            raise SkillValidationError(_explain(skill, exc, args)) from exc
        return ValidatedCall(skill, parsed, call.label)

    def describe(self) -> list[dict[str, Any]]:
        return [s.describe() for s in self._skills.values()]

    def tool_schemas(self) -> list[dict[str, Any]]:
        """Skills as OpenAI-style function tools."""
        return [
            {
                "type": "function",
                "function": {
                    "name": s.tool_name,
                    "description": s.description,
                    "parameters": s.parameters_schema(),
                },
            }
            for s in self._skills.values()
        ]


def _explain(skill: Skill, exc: ValidationError, args: Mapping[str, Any]) -> list[str]:
    fields = skill.args_model.model_fields
    allowed = ", ".join(fields) or "none"
    problems = []
    for err in exc.errors():
        name = ".".join(str(p) for p in err["loc"]) or "(arguments)"
        got = err.get("input")
        if err["type"] == "extra_forbidden":
            problems.append(
                f"{skill.name}: unknown argument {name!r}; allowed arguments: {allowed}"
            )
            continue
        if err["type"] == "missing":
            problems.append(
                f"{skill.name}: missing required argument {name!r}{_hint(fields, name)}"
            )
            continue
        if isinstance(err.get("ctx", {}).get("error"), UnitError):
            problems.append(f"{skill.name}: {name!r}: {err['ctx']['error']}")
            continue
        if isinstance(got, float) and not math.isfinite(got):
            problems.append(f"{skill.name}: {name!r} must be a finite number, got {got}")
            continue
        message = err["msg"].lower()
        given = args.get(name, got)
        shown = repr(got) if given is got or given == got else f"{given!r} = {got!r}"
        problems.append(f"{skill.name}: {name!r} {message} (got {shown}){_hint(fields, name)}")
    return problems


def _hint(fields: Mapping[str, Any], name: str) -> str:
    info = fields.get(name)
    return f"; {name} is {info.description}" if info is not None and info.description else ""
