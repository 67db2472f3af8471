"""Plans: what a planner proposes. Nothing here touches the robot."""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass, field, replace
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
    `branch` (guards only): the "if ... otherwise ..." the guarded step belongs to. The steps
    of one branch share it, and it is decided once, when its first step is reached; 0 when the
    plan does not say (see `branches`).
    """

    when: str
    kind: str
    name: str = ""
    within: float | None = None
    percent: float | None = None
    words: str = ""
    branch: int = 0

    @property
    def condition(self) -> tuple[str, str, float | None, float | None]:
        """What it tests, whatever its `when` and words: two guards that test one condition
        are alike here ("if the ball is seen" and its "otherwise")."""
        return (self.kind, self.name, self.within, self.percent)

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
        if self.branch:
            out["branch"] = self.branch
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


def branches(guards: Sequence[Watch | None]) -> list[int]:
    """The branch of each step, given its guard (0: it has none). A guard that names its branch
    (`Watch.branch`) keeps it; guards that name none (a model's conditions, plans made before
    guards had branches) are grouped: a run of consecutive guarded steps that test one
    condition is one branch, its "if" and its "otherwise" steps alike. One branch is decided
    once, when its first step is reached: exactly one of its ways runs."""
    number = max((g.branch for g in guards if g is not None), default=0)
    out: list[int] = []
    before: Watch | None = None  # the unnamed guard of the step before
    for guard in guards:
        if guard is None or guard.branch:
            out.append(guard.branch if guard is not None else 0)
            before = None
            continue
        if before is None or before.condition != guard.condition:
            number += 1
        out.append(number)
        before = guard
    return out


def branch_problems(guards: Sequence[Watch | None], first: int = 1) -> list[str]:
    """Why the guards' branches cannot be decided once each (empty: they can): a branch is a
    whole number, and the steps of one branch test one condition."""
    for i, g in enumerate(guards, first):
        if g is not None and (
            isinstance(g.branch, bool) or not isinstance(g.branch, int) or g.branch < 0
        ):
            return [f"step {i}: a guard's branch is a whole number (0: not said), got {g.branch!r}"]
    problems: list[str] = []
    tested: dict[int, tuple[int, Watch]] = {}
    for i, (g, b) in enumerate(zip(guards, branches(guards), strict=True), first):
        if g is None:
            continue
        where, one = tested.setdefault(b, (i, g))
        if one.condition != g.condition:
            problems.append(
                f"steps {where} and {i} are one branch ({b}) but test different conditions "
                f"({one.describe()}; {g.describe()}): a branch tests one condition"
            )
    return problems


def branch_ways(guards: Sequence[Watch | None], first: int = 1) -> list[str]:
    """Each branch's ways in words, for a dry run: "one way runs, decided when step 1 is
    reached: step 1 if the red ball is visible, otherwise step 2"."""
    ways: dict[int, dict[bool, list[int]]] = {}
    said: dict[int, str] = {}
    for i, (g, b) in enumerate(zip(guards, branches(guards), strict=True), first):
        if g is None:
            continue
        ways.setdefault(b, {True: [], False: []})[g.when == "if"].append(i)
        if g.when == "if" and b not in said:
            said[b] = g.words or g.describe()
    out = []
    for b, way in ways.items():
        start = min(way[True] + way[False])
        taken = _steps(way[True]) + " " + said.get(b, "if its condition holds")
        if way[False]:
            taken += f", otherwise {_steps(way[False])}"
        out.append(f"one way runs, decided when step {start} is reached: {taken}")
    return out


def _steps(numbers: list[int]) -> str:
    if not numbers:
        return "nothing"
    return ("step " if len(numbers) == 1 else "steps ") + ", ".join(map(str, numbers))


def with_branches(steps: Sequence[SkillCall]) -> list[SkillCall]:
    """`steps` with each guard naming its branch (`branches`), as a record shows them."""
    return [
        replace(s, guard=replace(s.guard, branch=b))
        if isinstance(s.guard, Watch) and s.guard.branch != b
        else s
        for s, b in zip(steps, branches([_guard(s) for s in steps]), strict=True)
    ]


def _guard(step: SkillCall) -> Watch | None:
    return step.guard if isinstance(step.guard, Watch) else None


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
