"""Plans: what a planner proposes. Nothing here touches the robot."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Any

from .errors import PlanningError as PlanningError
from .usage import Usage as Usage

if TYPE_CHECKING:
    from .config import AgentConfig

WATCH_KINDS = ("seen", "in_the_way", "battery_below", "operator_stop")
WATCH_WHEN = ("until", "unless")
GUARD_WHEN = ("if", "if_not")  # a step's guard: it runs only if the condition holds (or not)


@dataclass(frozen=True)
class Watch:
    """A condition the runtime watches while a step runs, at control rate (never a model).

    `when`: "until" ends the step when the condition holds and the mission goes on; "unless"
    (also "stop if") stops the step and ends the mission there, saying why. A watch can only
    shorten a step: the plan is checked as if it never fired.
    `kind`: "seen" (`name` in view, within `within` metres when given), "in_the_way"
    (something in the robot's path within `within` metres of its body), "battery_below"
    (`percent`), "operator_stop" (a person's stop from any interface: the web, ROS, MCP, the
    CLI; "until I say stop" then ends the step as asked rather than as a cancelled mission).
    `words`: the request's words for it, for people.
    """

    when: str
    kind: str
    name: str = ""
    within: float | None = None
    percent: float | None = None
    words: str = ""

    def to_dict(self) -> dict[str, Any]:
        out: dict[str, Any] = {"when": self.when, "kind": self.kind}
        if self.name:
            out["name"] = self.name
        if self.within is not None:
            out["within"] = self.within
        if self.percent is not None:
            out["percent"] = self.percent
        if self.words:
            out["words"] = self.words
        return out

    def describe(self) -> str:
        """In a person's words: "until red ball is seen", "unless something is in the way
        (within 1 m)", "if the battery is below 30%", "if not ... (otherwise)"."""
        if self.kind == "seen":
            what = f"{self.name or 'anything'} is seen"
            if self.within is not None:
                what += f" within {self.within:g} m"
        elif self.kind == "in_the_way":
            what = f"something is in the way (within {self.within or 0:g} m)"
        elif self.kind == "operator_stop":
            what = "a person says stop"
        else:
            what = f"the battery is below {self.percent or 0:g}%"
        if self.when == "if_not":
            return f"otherwise (not: {what})"
        return f"{self.when} {what}"


@dataclass(frozen=True)
class SkillCall:
    """One proposed step: a registered skill name and its (not yet validated) arguments, and
    the conditions watched while it runs."""

    skill: str
    args: dict[str, Any] = field(default_factory=dict)
    label: str = ""  # the words of the request this step came from, for people
    watches: tuple[Watch, ...] = ()
    # Decided when the step is reached: it runs only if this holds ("if"), or does not
    # ("if_not": an "otherwise" branch); else it is skipped, saying why.
    guard: Watch | None = None

    def to_dict(self) -> dict[str, Any]:
        # A language model may propose anything; keep the record JSON-safe whatever it is.
        args = dict(self.args) if isinstance(self.args, dict) else {"_invalid": repr(self.args)}
        out: dict[str, Any] = {"skill": self.skill, "args": args, "label": self.label}
        if self.watches:
            out["watches"] = [w.to_dict() for w in self.watches]
        if isinstance(self.guard, Watch):
            out["guard"] = self.guard.to_dict()
        return out


@dataclass
class Plan:
    """An ordered list of skill calls for one request, plus what the planner assumed."""

    steps: list[SkillCall]
    text: str = ""
    notes: list[str] = field(default_factory=list)  # assumptions, e.g. "no distance given: 1 m"
    usage: Usage = field(default_factory=Usage)
    planner: str = ""  # the planner's name, e.g. "offline" or "llamacpp:qwen2.5"
    planned_by: str = ""  # offline | llm | explicit: the kind of planner that made it

    def to_dict(self) -> dict[str, Any]:
        return {
            "text": self.text,
            "planner": self.planner,
            "planned_by": self.planned_by,
            "steps": [s.to_dict() for s in self.steps],
            "notes": list(self.notes),
        }


def oversize(steps: Sequence[SkillCall], limits: AgentConfig) -> list[str]:
    """Why `steps` carry more than one plan may, naming each limit (`agent.max_steps`,
    `max_watches_per_step`, `max_watches`, `max_args_chars`); [] when they do not. The work is
    bounded by the limits whatever the steps hold: a plan of 10,000 steps, or one step of
    10,000 watches, is refused before any step is read further."""
    if len(steps) > limits.max_steps:
        return [
            f"the plan has {len(steps)} steps; at most {limits.max_steps} are allowed "
            "(agent.max_steps)"
        ]
    problems: list[str] = []
    total = 0
    for index, call in enumerate(steps, start=1):
        watches = getattr(call, "watches", ())
        here = (len(watches) if isinstance(watches, (tuple, list)) else 0) + (
            getattr(call, "guard", None) is not None
        )
        total += here
        if here > limits.max_watches_per_step:
            problems.append(
                f"step {index} carries {here} conditions; at most "
                f"{limits.max_watches_per_step} are allowed (agent.max_watches_per_step)"
            )
        if _carries(getattr(call, "args", None), limits.max_args_chars) > limits.max_args_chars:
            problems.append(
                f"step {index}: its arguments carry more than {limits.max_args_chars} "
                "characters; at most that many are allowed (agent.max_args_chars)"
            )
    if total > limits.max_watches:
        problems.append(
            f"the plan carries {total} conditions; at most {limits.max_watches} are allowed "
            "(agent.max_watches)"
        )
    return problems


def _carries(value: Any, limit: int) -> int:
    """Characters `value` carries (strings and keys by their length, anything else as one),
    counted without recursion and only until it passes `limit`."""
    size, stack = 0, [value]
    while stack and size <= limit:
        item = stack.pop()
        if isinstance(item, str):
            size += len(item)
        elif isinstance(item, Mapping):
            size += 1
            stack.extend(item.keys())
            stack.extend(item.values())
        elif isinstance(item, (list, tuple)):
            size += 1
            stack.extend(item)
        else:
            size += 1
    return size
