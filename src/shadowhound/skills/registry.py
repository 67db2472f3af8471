"""The skill registry: the one source of truth for what the robot can be asked to do.

Each skill has typed arguments (a pydantic model), a description, a timeout on the robot's
clock, and a prediction of where it takes the robot (used by the safety check before a plan
runs). The CLI listing, the web page, language-model tool schemas and the offline planner all
read this registry.

A skill also declares every fact the rest of the house needs about it (whether it walks or
runs standing, the posture it leaves, whether it may run on a low battery, what makes a call
risky, the time it surely takes, whether its output is an answer for the user, what memory
keeps of it, how a call is said in words). The governor, `result.compose_response`, the memory
and the planners' messages read these declarations and never a skill's name, so adding a skill
is one file: its `Skill(...)` in a module's `SKILLS` (listed once in `default_registry`), or one
`SkillRegistry.register` call for a skill of your own.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Iterable, Mapping
from dataclasses import dataclass
from typing import TYPE_CHECKING, Any, get_args

from pydantic import ValidationError

from ..errors import SkillValidationError
from ..plan import SkillCall, Watch
from ..state import Posture
from ..units import UnitError
from .arguments import SkillArgs, typical_value

if TYPE_CHECKING:
    from ..state import Pose2D
    from .context import PlanEnv, SkillContext


Runner = Callable[["SkillContext", Any], str]
Predictor = Callable[["Pose2D", Any, "PlanEnv"], list["Pose2D"]]
Timeout = Callable[[Any, "PlanEnv"], float]
Seconds = Callable[[Any], float]  # of a call's arguments
Words = Callable[[Any], str]  # of a call's arguments
Forecast = Callable[[Any, "PlanEnv"], str]  # of a call's arguments, in a mission


@dataclass(frozen=True)
class Skill:
    """A robot capability. `run` returns a short sentence saying what happened.

    The fields after `predict` are what the rest of the house knows of the skill (the module
    docstring says who reads them); the defaults fit a skill that keeps the robot still.
    """

    name: str
    description: str
    args_model: type[SkillArgs]
    run: Runner
    timeout: float | Timeout = 30.0  # seconds on the robot's clock
    moves: bool = False  # may translate or rotate the robot (then it also runs standing)
    predict: Predictor | None = None  # poses the robot passes through, for the safety check
    # Runs standing although it does not walk (a trick): the robot stands up first
    # (motion.auto_stand), or the governor refuses the step while it is sitting or lying.
    needs_standing: bool = False
    # The posture the skill leaves the robot in (body.sit); None: standing after a skill that
    # runs standing, else the posture it found.
    posture: Posture | None = None
    low_battery: bool = False  # may run below safety.battery_floor: it walks nowhere
    # Why this call needs a person's approval (or safety.allow_risky_tricks); "" when it does not.
    risk: Words | None = None
    # Robot seconds a call surely takes in place (a trick's routine): counted, with the time
    # its path takes at the speed cap, toward safety.max_mission_duration before it runs.
    seconds: Seconds | None = None
    # Seconds a call holds still because it was asked to: at most safety.max_wait, and
    # counted toward the mission's time like `seconds`.
    waits: Seconds | None = None
    # Its output answers the user (a view, a status, a list): the mission's response says it
    # as a sentence of its own instead of listing it among what was done.
    reports: bool = False
    # Retrieval memory keeps each successful output as this kind (observation, fact, mission).
    remembered_as: str | None = None
    # A call in a few words ("move forward 2 m"); default: the name. With typical arguments it
    # is also the mission the chat offers as an example (`example`), so say it as people do.
    phrase: Words | None = None
    # What the plan check cannot predict of a call, in words ("would look for the chair for up
    # to 120 s and 20 m ..."), "" when it can: a dry run says it.
    forecast: Forecast | None = None
    # The stick axis of teleoperation this skill's motion is ("forward", "sideways", "turn"):
    # the governor's rules for the skill hold for that axis of the pad (teleop.py).
    drives: str | None = None

    def __post_init__(self) -> None:
        if self.moves and self.low_battery:  # below the battery floor nothing may walk
            raise ValueError(
                f"skill {self.name!r} moves the robot, so it cannot be allowed "
                "on a low battery (low_battery=True)"
            )

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
            prop.pop("examples", None)  # for the chat's examples (`example`); tokens to a model
        schema.setdefault("properties", {})
        schema["additionalProperties"] = False
        return schema

    def timeout_for(self, args: SkillArgs, env: PlanEnv) -> float:
        return self.timeout(args, env) if callable(self.timeout) else float(self.timeout)

    @property
    def runs_standing(self) -> bool:
        """Whether the robot must be standing for it (every skill that walks or turns is)."""
        return self.moves or self.needs_standing

    def posture_after(self, before: Posture) -> Posture:
        """The posture a call leaves the robot in, from the posture it starts in."""
        if self.posture is not None:
            return self.posture
        return Posture.STANDING if self.runs_standing else before

    def least_seconds(self, args: SkillArgs) -> float:
        """Robot seconds a call surely takes besides walking (its trick, its wait)."""
        return sum(float(f(args)) for f in (self.seconds, self.waits) if f is not None)

    def why_risky(self, args: SkillArgs) -> str:
        """Why a call needs approval ("" when it does not)."""
        return self.risk(args) if self.risk is not None else ""

    def say(self, args: SkillArgs) -> str:
        """A call in a few words for people ("move forward 2 m"); the name without a phrase."""
        return self.phrase(args) if self.phrase is not None else self.name

    def example(self) -> str | None:
        """This skill asked for in words with typical arguments ("turn left 90 degrees"), for
        people who ask what the robot can do; None when it has no `phrase`, or its arguments
        have no typical values (free text such as a note). A field's declared `examples` come
        first (words to say: the call without them means something else)."""
        if self.phrase is None:
            return None
        fields = self.args_model.model_fields
        required = {n: typical_value(f) for n, f in fields.items() if f.is_required()}
        optional = {n: typical_value(f) for n, f in fields.items() if not f.is_required()}
        shown = {n: f.examples[0] for n, f in fields.items() if f.examples}
        # The fewest arguments that make a valid call: the required ones, else every typical one.
        for values in (required | shown, required, required | optional):
            given = {n: v for n, v in values.items() if v is not None}
            try:
                return self.say(self.args_model(**given))
            except (ValidationError, UnitError):
                continue
        return None

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
    watches: tuple[Watch, ...] = ()  # checked by checking.check_plan against the robot
    guard: Watch | None = None  # run only if it holds (or not): decided when reached

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

    def tricks(self) -> frozenset[str]:
        """The trick names `body.sport` takes here: the robot's tricks (empty: it has none)."""
        sport = self._skills.get("body.sport")
        if sport is None:
            return frozenset()
        return frozenset(get_args(sport.args_model.model_fields["trick"].annotation))

    def find(self, name: str) -> Skill | None:
        """The skill called `name` (or its tool name), None when there is none."""
        return self._skills.get(name) or self._by_tool_name(name)

    def get(self, name: str) -> Skill:
        skill = self.find(name)
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
        return ValidatedCall(
            skill, parsed, call.label, _watches(call.watches), _guard(getattr(call, "guard", None))
        )

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


def _watches(watches: Any) -> tuple[Watch, ...]:
    """A step's watches as given: a tuple of plan.Watch (what each means is checked against the
    robot by checking.check_plan)."""
    if watches is None:
        return ()
    if not isinstance(watches, (tuple, list)) or not all(isinstance(w, Watch) for w in watches):
        raise SkillValidationError([f"a step's watches must be conditions, got {watches!r:.80}"])
    return tuple(watches)


def _guard(guard: Any) -> Watch | None:
    if guard is None or isinstance(guard, Watch):
        return guard
    raise SkillValidationError([f"a step's guard must be a condition, got {guard!r:.80}"])


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
