"""Memory skills: teach and forget places, list them, teach facts, recall what happened."""

from __future__ import annotations

from pydantic import Field

from ..errors import PlanProblem, RecallStoreError, SkillError
from ..memory.places import known_places, normalize_place
from ..state import Pose2D, position_unknown
from .arguments import NoArgs, SkillArgs
from .context import PlanEnv, SkillContext
from .registry import Skill

_NAME = r"^[^\W\d_][\w' -]*$"


class PlaceArgs(SkillArgs):
    name: str = Field(
        min_length=1, max_length=60, pattern=_NAME, description="place name, e.g. kitchen"
    )


class NoteArgs(SkillArgs):
    text: str = Field(min_length=1, max_length=1000, description="a fact to remember")


class RecallArgs(SkillArgs):
    query: str = Field(min_length=1, max_length=500, description="what to look for")


def _memory(ctx: SkillContext):  # type: ignore[no-untyped-def]
    if ctx.memory is None:
        raise SkillError("this agent has no memory attached")
    return ctx.memory


def _unknown_here(pose: Pose2D) -> str:
    """Why no place can be remembered at `pose` ("" when one can): odometry that lies."""
    why = position_unknown(pose)
    return f"{why}: cannot remember a place there" if why else ""


def _remember(ctx: SkillContext, a: PlaceArgs) -> str:
    st = ctx.robot.get_state()
    if why := _unknown_here(st.pose):
        raise SkillError(why)
    book = _memory(ctx).places
    key = book.remember(a.name, st.x, st.y, st.yaw)
    ctx.env.places[key] = (st.x, st.y)
    kept = "" if book.persistent else " (for this session; set memory.enabled to keep it)"
    return f"remembered this spot as the {key} at x={st.x:.2f} m, y={st.y:.2f} m{kept}"


def _predict_remember(pose: Pose2D, a: PlaceArgs, env: PlanEnv) -> list[Pose2D]:
    if why := _unknown_here(pose):
        raise PlanProblem(why)
    env.places[normalize_place(a.name)] = (pose.x, pose.y)  # later steps may go there
    return []


def _forget(ctx: SkillContext, a: PlaceArgs) -> str:
    key = normalize_place(a.name)
    if _memory(ctx).places.forget(key):
        ctx.env.places.pop(key, None)
        if key in ctx.config.places:
            return f"forgot the taught {key}; the profile's {key} remains"
        return f"forgot the {key}"
    if key in ctx.config.places:
        raise SkillError(f"the {key} comes from the profile (places:); remove it there")
    taught = ", ".join(_memory(ctx).places.all()) or "none"
    raise SkillError(f"I know no taught place called {key!r}; taught places: {taught}")


def _predict_forget(pose: Pose2D, a: PlaceArgs, env: PlanEnv) -> list[Pose2D]:
    key = normalize_place(a.name)
    if key not in env.config.places:
        env.places.pop(key, None)
    return []


def _list(ctx: SkillContext, _a: NoArgs) -> str:
    known = known_places(ctx.config.places, _memory(ctx).places)
    parts = [
        f"{n} ({p.x:.2f}, {p.y:.2f}{', taught' if p.source == 'taught' else ''})"
        for n, p in known.items()
    ]
    return (
        "Known places: "
        + ", ".join([*parts, "start (where a mission begins)", "home (0, 0)"])
        + "."
    )


def _note(ctx: SkillContext, a: NoteArgs) -> str:
    memory = _memory(ctx)
    recall = memory.recall
    if recall is None and memory.recall_problem:
        raise SkillError(f"retrieval memory is off for this run: {memory.recall_problem}")
    if recall is None:
        raise SkillError(
            "retrieval memory is off: set memory.enable_rag: true (and install "
            "the 'memory' extra) to teach me facts"
        )
    st = ctx.robot.get_state()
    try:
        recall.add(a.text, "fact", x=st.x, y=st.y)
    except RecallStoreError as exc:
        memory.turn_recall_off(exc)
        raise SkillError(f"retrieval memory is off for this run: {exc}") from exc
    return f"I will remember that {a.text}"


def _recall(ctx: SkillContext, a: RecallArgs) -> str:
    found = _memory(ctx).search(a.query)
    if not found:
        return "I remember nothing about that."
    return "I remember: " + " | ".join(found)


SKILLS = (
    Skill(
        "places.remember",
        "Remember the robot's current position under a name.",
        PlaceArgs,
        _remember,
        timeout=5.0,
        predict=_predict_remember,
    ),
    Skill(
        "places.forget",
        "Forget a taught place.",
        PlaceArgs,
        _forget,
        timeout=5.0,
        predict=_predict_forget,
    ),
    Skill(
        "places.list", "List the places the robot knows.", NoArgs, _list, timeout=5.0, reports=True
    ),
    Skill(
        "memory.note",
        "Remember a fact the user teaches (needs retrieval memory).",
        NoteArgs,
        _note,
        timeout=30.0,
    ),
    Skill(
        "memory.recall",
        "Recall past missions, facts and observations about a topic.",
        RecallArgs,
        _recall,
        timeout=30.0,
        reports=True,
    ),
)
