"""Conditions a request states, so that none is ever silently dropped.

People give robots conditions: "walk forward until you see the red ball", "walk to the kitchen
unless someone is in the way", "if the battery is low go to the dock, otherwise patrol", "stop
when you see a person", "follow me". A condition is part of what the person allowed: a plan
must express it, or the mission is refused. The offline planner refuses conditions clause by
clause; the model planners' plans cannot express one yet (a step has no watch), so
`unhonoured` names every condition a request states and the model planners refuse it before
anything moves, whatever the model would have proposed.

`stated` reads kinds of sentences, not listed ones. A condition is one of:
- a bound or a guard: until, unless, as long as, while (with a clause: "while the battery
  is above 50%"), in case, provided, depending on, "wait for the person";
- a branch: if (also "if so"), otherwise, or else;
- a trigger: when, whenever, once, as soon as, the moment, every time, after / before,
  followed by something that happens ("when you see a cat", "once the person leaves");
- a watch or a follow: "watch for people", "keep an eye on the door", "follow the person",
  "keep following me", "come with me".

And it is not a condition when the words only look like one:
- an embedded question: "tell me if you see a cat", "check whether the door is open", "ask
  me if ...", "let me know if ...", "tell me when you last saw the ball";
- a question: "when did you see the ball?", "what if ...";
- a courtesy or a hedge: "if you can", "if possible", "as soon as possible", "if any";
- a sequence: "when you are done", "once you get there", "after you stand up";
- a repeat with no end ("keep patrolling", "forever"): the mission's limits end it, as they
  end react mode's loop; it states nothing to watch for;
- a count or a time: "wave once", "at once", "wait a while", "wait for 5 seconds";
- words to say or remember: quoted text, "say that ...", "remember that ...".

Misspelt condition words are read as such ("untill", "unles", "otherwize", "folow"), with the
same edit distance the offline planner forgives, never from a real word ("whole", "fellow").
"""

from __future__ import annotations

from dataclasses import dataclass

from ..plan import Plan, PlanningError, Usage
from ._condition_words import clause_end, scan, tokens

MAX_QUOTE = 60  # characters of a condition quoted back to the person


@dataclass(frozen=True)
class Condition:
    """One condition a request states: its kind and its words as the person wrote them."""

    kind: str  # until | unless | if | otherwise | while | as long as | when | follow | ...
    words: str


def stated(text: str) -> list[Condition]:
    """The conditions `text` states, in order (none for a plain request)."""
    if not isinstance(text, str):
        return []
    read = tokens(text)
    found: list[Condition] = []
    taken: set[int] = set()
    for index, kind in scan([t.word for t in read]):
        if index in taken:
            continue
        end = clause_end(read, index)
        taken.update(range(index, end))
        words = text[read[index].start : read[end - 1].end]
        if len(words) > MAX_QUOTE:
            words = words[: MAX_QUOTE - 3].rstrip() + "..."
        found.append(Condition(kind, words))
    return found


def unhonoured(text: str, plan: Plan | None) -> list[str]:
    """The words of each condition `text` states that `plan` does not express; [] when the
    plan expresses them all (or there are none). No plan (None) expresses none.

    A plan expresses conditions through its steps' watches and guards, and a follow through a
    step that follows.
    """
    conditions = stated(text)
    if not conditions or plan is None:
        return [c.words for c in conditions]
    return [c.words for c in conditions if not _expresses(plan, c)]


def refusal(words: list[str], usage: Usage | None = None) -> PlanningError:
    """The refusal of a request whose conditions no plan can honour, naming them."""
    quoted = ", ".join(f"'{w}'" for w in words)
    several = len(words) > 1
    return PlanningError(
        f"This request states {'conditions' if several else 'a condition'} ({quoted}) that I "
        "cannot watch for yet, and I will not plan it as if "
        f"{'they were' if several else 'it were'} not there. Ask without "
        f"{'them' if several else 'it'}, saying exactly what to do (for example 'walk forward "
        "1 meter and tell me what you see'), and end a motion early with 'stop' or the e-stop.",
        not_understood=list(words),
        usage=usage,
    )


def _expresses(plan: Plan, condition: Condition) -> bool:
    """Whether `plan` carries `condition`: a follow by a step that follows, a branch by a
    guarded step, any other condition by a step's watch or guard."""
    steps = plan.steps
    if condition.kind == "follow":
        return any(step.skill == "nav.follow" for step in steps)
    guarded = any(getattr(step, "guard", None) is not None for step in steps)
    if condition.kind == "otherwise":
        return guarded  # a branch ("stop if ..." is a watch: below)
    return guarded or any(getattr(step, "watches", None) for step in steps)
