"""Offline planner: plain English requests to skill calls by rules, with no language model.

It recognises kinds of requests (postures, moves, turns, go-to, shapes, patrols, waits, tricks,
questions) rather than fixed sentences, and records every assumption in `Plan.notes`. It never
refuses on safety grounds; limits and risky tricks are the safety layer's business.

This module decides what each kind of request means. Reading the English is done by `_english`
(clauses, clean-up, tokens), `_phrases` (patterns per kind of clause), `_vocabulary` (word
tables) and `_numbers` (units, number words); `_errors` words the replies when a plan fails.

Long because: it is the one place that says what each kind of request means (a method per
kind, sharing the clause loop's notes and last verb); the reading of English lives in the
modules above.
"""

from __future__ import annotations

import re
from collections.abc import Collection
from dataclasses import replace
from functools import cache
from typing import Any

from shadowhound.plan import Plan, PlanningError, SkillCall, Watch
from shadowhound.planning import _english as en
from shadowhound.planning import _numbers as nums
from shadowhound.planning import _phrases as phrases
from shadowhound.planning import _spelling as spelling
from shadowhound.planning import _vocabulary as vocab
from shadowhound.planning import _watches as watching
from shadowhound.planning import conditions
from shadowhound.planning._errors import CAPABILITIES, NotUnderstood, describe, failure
from shadowhound.planning._memory_phrases import memory_steps
from shadowhound.planning._speech_phrases import SpeechRequest, speech_request
from shadowhound.planning._text import canon
from shadowhound.skills import default_registry
from shadowhound.units import format_number

__all__ = ["CAPABILITIES", "MAX_CHARS", "MAX_STEPS", "RulePlanner"]

MAX_CHARS = 2000
MAX_STEPS = 1000  # guards memory against "repeat 1000000 times"; motion limits live elsewhere

_fmt = format_number
# What a clause asks: its steps (None: repeat everything so far), repeat count, how, its verb.
_Read = tuple[list[SkillCall] | None, int, str, str]


class RulePlanner:
    """Plans English requests with hand-written rules; fast, deterministic and offline."""

    name = "offline"
    kind = "offline"
    needs_context = False  # plans from the words alone

    def __init__(
        self,
        *,
        default_distance: float = 1.0,
        default_turn_degrees: float = 90.0,
        default_wait: float = 1.0,
        default_square_side: float = 1.0,
        tricks: Collection[str] | None = None,
    ) -> None:
        self.default_watch_distance = 5.0  # metres a walk "until ..." goes at most
        # The robot's tricks (its registry's body.sport); None: any trick there are words for.
        self.tricks = None if tricks is None else frozenset(tricks)
        self.default_distance = float(default_distance)
        self.default_turn_degrees = float(default_turn_degrees)
        self.default_wait = float(default_wait)
        self.default_square_side = float(default_square_side)

    def plan(self, text: str, context: object | None = None) -> Plan:
        """Turn `text` into a Plan; `context` (robot state) is not used by this planner."""
        if not isinstance(text, str):
            raise PlanningError(f"The mission must be text, not {type(text).__name__}.")
        if len(text) > MAX_CHARS:
            raise PlanningError(
                f"The mission is {len(text)} characters long; the limit is {MAX_CHARS}. "
                "Split it into shorter missions."
            )
        if not text.strip():
            raise PlanningError(
                "The mission is empty. Tell me what to do, for example 'walk forward 1 meter'. "
                + CAPABILITIES
            )
        steps: list[SkillCall] = []
        notes: list[str] = []
        failed: list[tuple[str, str]] = []
        last_verb = ""
        previous = 0  # where the last clause's steps begin
        guard: Watch | None = None  # "if ...": the clauses after it run only if it holds
        branch: Watch | None = None  # the last "if", for an "otherwise"
        for label in en.split_clauses(text):
            norm_if = en.normalize(label)[0]
            opened = watching.IF.match(norm_if) or _when_branch(norm_if)
            other = watching.OTHERWISE.match(norm_if)
            if opened or other:
                try:
                    if opened:  # a new branch: its steps, "otherwise" ones too, share its id
                        guard, taken = self._branch(opened["rest"], label, notes)
                        guard = replace(guard, branch=_last_branch(steps) + 1)
                        branch = guard
                    else:
                        if branch is None:
                            raise NotUnderstood("'otherwise' needs an 'if' before it")
                        guard = replace(branch, when="if_not", words="otherwise")
                        taken = self._then(other["rest"] or "", label, notes) if other else []
                        branch = None
                except NotUnderstood as exc:
                    failed.append((label, exc.reason))
                    continue
                _check_size(steps, len(steps) + len(taken))
                previous = len(steps)
                steps.extend(_guarded(s, guard) for s in taken)
                continue
            speech = speech_request(label)
            if speech is not None:
                try:
                    said = self._speech(speech, label, notes, steps)
                except NotUnderstood as exc:
                    failed.append((label, exc.reason))
                    continue
                _check_size(steps, len(steps) + len(said))
                steps.extend(_guarded(s, guard) for s in said)
                last_verb = ""
                continue
            remembered = memory_steps(label)
            if remembered is not None:
                steps.extend(_guarded(s, guard) for s in remembered)
                last_verb = ""
                continue
            try:
                norm, clause_notes = en.normalize(label)
                stop_if = watching.STOP_IF.match(norm)
                if stop_if:  # "(and) stop if you see a person": watches the clause before
                    if not steps:
                        raise NotUnderstood("say what to do before when to stop")
                    watch = watching.watch_of("stop if", stop_if["cond"])
                    steps[previous:] = [_watched(s, watch) for s in steps[previous:]]
                    continue
                read = self._forgiving(norm, label, clause_notes, last_verb, bool(steps))
                if read is None:
                    continue  # only fillers such as "please" or "hey dog"
                new, count, how, last_verb = read
                if new is None:  # "repeat that": everything so far, again
                    total = count + 1 if how == "more" else (count if how == "times" else 2)
                    _check_size(steps, len(steps) * total)
                    steps = _repeated(steps, total)
                    notes.extend(clause_notes)
                    continue
            except NotUnderstood as exc:
                failed.append((label, exc.reason))
                last_verb = ""
                continue
            except ValueError as exc:  # a number too large to be finite
                failed.append((label, str(exc)))
                last_verb = ""
                continue
            if count > 1:
                if len(new) == 1 and new[0].skill == "nav.patrol":
                    laps = new[0].args["laps"] * count
                    new = [SkillCall("nav.patrol", {"laps": laps}, label)]
                else:
                    _check_size(steps, len(steps) + len(new) * count)
                    new = new * count
            _check_size(steps, len(steps) + len(new))
            previous = len(steps)
            steps.extend(_guarded(s, guard) for s in new)
            notes.extend(clause_notes)
        if failed:
            raise failure(steps, failed)
        if not steps:
            raise PlanningError(
                f"I found no request in {text.strip()[:80]!r}. " + CAPABILITIES,
                not_understood=[text.strip()[:200]],
            )
        plan = Plan(
            steps=steps,
            text=text,
            notes=list(dict.fromkeys(notes)),
            planner=self.name,
            planned_by=self.kind,
        )
        missing = conditions.unhonoured(text, plan)
        if missing:  # a condition read past ("every time you see a cat, sit"): never dropped
            raise conditions.refusal(missing)
        return plan

    # ---- one clause ---------------------------------------------------------------------------

    def _speech(
        self, speech: SpeechRequest, label: str, notes: list[str], before: list[SkillCall]
    ) -> list[SkillCall]:
        """Steps for a clause that asks to speak: a question's steps then its answer said, the
        words said (a greeting with the wave), or an earlier step's answer said."""
        say = SkillCall("voice.say", {}, label)
        if speech.question is not None:
            asked = self._question(speech.question, notes, bool(before))
            if asked:
                return [*asked, say]
            if speech.text is None:
                raise NotUnderstood(
                    "I can say words aloud, or the answer to a question I understand "
                    "('say what you see', 'tell me where you are out loud')"
                )
        if speech.text is not None:
            said = SkillCall("voice.say", {"text": speech.text}, label)
            steps = [said]
            if speech.greeting and self._offers("hello"):  # a greeting is said with the wave
                steps.append(SkillCall("body.sport", {"trick": "hello"}, label))
            _check_size(before, len(before) + len(steps) * speech.count)
            return steps * speech.count
        if not any(_answers(s) for s in before):
            raise NotUnderstood(
                "nothing before it gives an answer to say; ask first, e.g. 'tell me what you "
                "see and say it out loud'"
            )
        return [say]

    def _question(self, question: str, notes: list[str], after_steps: bool) -> list[SkillCall]:
        """The steps that answer `question` (planned as any clause), or [] when it is not
        understood or its steps give no answer."""
        asked = memory_steps(question)
        tried: list[str] = []
        if asked is None:
            try:
                norm, tried = en.normalize(question)
                read = self._forgiving(norm, question, tried, "", after_steps)
            except (NotUnderstood, ValueError):
                return []
            if read is None or read[0] is None or read[1] != 1:
                return []
            asked = read[0]
        if not any(_answers(s) for s in asked):
            return []
        notes.extend(tried)
        return asked

    def _forgiving(
        self, norm: str, label: str, notes: list[str], last_verb: str, after_steps: bool
    ) -> _Read | None:
        """`_read`, and if the clause is not understood as written, `_read` again with its
        misspellings read as the planner's own words; the notes say what was read as what.
        Raises NotUnderstood naming the words that stand in the way."""
        tried = list(notes)
        try:
            read = self._read(norm, label, tried, last_verb, after_steps)
        except NotUnderstood as exc:
            reason = exc.reason
        else:
            notes[:] = tried
            return read
        reading = spelling.read(en.normalize(label, digits=False)[0])
        understood = []
        for text, fixes in reading.alternatives():
            tried = list(notes)
            try:
                read = self._read(nums.to_digits(text), label, tried, last_verb, after_steps)
            except NotUnderstood as exc:
                reason = reason or exc.reason
                continue
            understood.append((read, tried, fixes))
        plans = {repr(read[:3] if read else read) for read, _, _ in understood}
        if len(plans) == 1:  # one reading makes sense (or all mean the same): take it, say so
            read, tried, fixes = understood[0]
            notes[:] = tried + [f"read '{a}' as '{b}' in '{label}'" for a, b in fixes]
            return read
        raise NotUnderstood("; ".join(r for r in (reason, reading.problems()) if r))

    def _read(
        self, norm: str, label: str, notes: list[str], last_verb: str, after_steps: bool
    ) -> _Read | None:
        """What a normalised clause asks: (steps, count, how, verb); steps None for "repeat
        all"; None for a clause of fillers only."""
        norm, count, how = phrases.repetition(norm)
        if not norm and not how:
            return None
        if not norm or phrases.REPEAT_ALL.match(norm):
            if not after_steps:
                raise NotUnderstood("there is nothing before it to repeat")
            return None, count, how, ""
        new, verb = self._clause(norm, label, notes, last_verb)
        if new is None:
            raise NotUnderstood()
        return new, count, how, verb

    def _clause(
        self, text: str, label: str, notes: list[str], last_verb: str
    ) -> tuple[list[SkillCall] | None, str]:
        """Steps for one normalised clause, or None if it is of no kind known here."""
        if phrases.STOP.match(text):
            return [SkillCall("nav.stop", {}, label)], ""
        if phrases.NEGATION.search(text):
            raise NotUnderstood("I do not plan around 'not'; say what to do instead")
        watched = watching.WATCHED.match(text)
        if watched and not phrases.CONDITION.search(watched["action"]):
            return self._watched(watched, label, notes, last_verb)
        lasting = watching.WHILE.match(text)
        if lasting:
            return self._while(lasting["rest"], label, notes, last_verb)
        condition = phrases.CONDITION.search(text)
        if condition:
            raise NotUnderstood(
                f"I do not plan around conditions ('{condition[0]}'); say what "
                "to do, or ask a language-model planner"
            )
        if phrases.TRAVEL.search(text):  # the status report says how far and how long
            return [SkillCall("sys.status", {}, label)], ""
        for handler in (
            self._wait,
            self._posture,
            self._trick,
            self._face,
            self._follow,
            self._find,
            self._goto,
            self._patrol,
        ):
            steps = handler(text, label, notes)
            if steps is not None:
                return steps, ""
        if phrases.SHAPE.search(text):
            return self._shape(text, label, notes), ""
        for pattern, replacement in phrases.ROTATE_PREFIXES:
            text = pattern.sub(replacement, text, count=1)
        m = phrases.MOTION.match(text)
        if m is None:
            verb = _implied_verb(text, last_verb)
            m = phrases.MOTION.match(f"{verb} {text}") if verb else None
        adverb = phrases.LEAD_ADVERB.match(text) if m is None else None
        if adverb is not None:
            m = phrases.MOTION.match(text[adverb.end() :])
        if m is not None:
            verb = canon(m["verb"])
            speed = vocab.ADVERBS[canon(adverb["adv"])] if adverb else None
            return self._motion(verb, m["rest"], label, notes, speed), verb
        if phrases.STATUS.search(text):
            return [SkillCall("sys.status", {}, label)], ""
        if phrases.LOOK_AROUND.search(text):
            return [SkillCall("perception.look_around", {"question": label}, label)], ""
        if phrases.DESCRIBE.search(text):
            return [SkillCall("perception.describe", {"question": label}, label)], ""
        if phrases.REPORT.match(text):
            return [SkillCall("sys.status", {}, label)], ""
        return None, ""

    def _branch(self, rest: str, label: str, notes: list[str]) -> tuple[Watch, list[SkillCall]]:
        """ "if CONDITION (then) ACTION": the guard and the action's steps (none: the action is
        in the clauses that follow). The shortest condition whose action plans wins."""
        for guard, tail in watching.split_condition(rest):
            try:
                return guard, self._then(tail, label, notes)
            except NotUnderstood:
                continue
        raise NotUnderstood(
            f"I do not plan around conditions ('if') such as '{rest}': {watching.CAN_WATCH}"
        )

    def _then(self, text: str, label: str, notes: list[str]) -> list[SkillCall]:
        """The steps of a branch's action (a sentence of its own)."""
        if not text.strip():
            return []
        try:
            plan = self.plan(text)
        except PlanningError as exc:
            raise NotUnderstood(exc.message) from exc
        notes.extend(plan.notes)
        return [replace(s, label=label) for s in plan.steps]

    def _watched(
        self, m: re.Match[str], label: str, notes: list[str], last_verb: str
    ) -> tuple[list[SkillCall] | None, str]:
        """ "ACTION until|unless CONDITION": the action's steps, each watching the condition.
        Waiting for something ("until you see ...") with no distance or angle given goes at
        most `default_watch_distance` metres or a full turn."""
        watch = watching.watch_of(m["when"], m["cond"])
        bounded = self
        if watch.when == "until":
            bounded = RulePlanner(
                default_distance=self.default_watch_distance,
                default_turn_degrees=360.0,
                default_wait=self.default_wait,
                default_square_side=self.default_square_side,
                tricks=self.tricks,
            )
        before = len(notes)
        steps, verb = bounded._clause(m["action"], label, notes, last_verb)
        if bounded is not self:  # a default reach is the most it goes, not where it ends
            notes[before:] = [
                n.replace(": used ", ": at most ").replace(": turned ", ": at most ")
                + f" ({watch.describe()})"
                for n in notes[before:]
            ]
        if not steps:
            raise NotUnderstood(f"I do not know what to do {m['when']} {m['cond']}")
        if watch.when == "until" and not phrases.LAPS.search(m["action"]):
            steps = [_keep_going(s) for s in steps]  # "patrol until ...": lap after lap
        return [_watched(s, watch) for s in steps], verb

    def _while(
        self, rest: str, label: str, notes: list[str], last_verb: str
    ) -> tuple[list[SkillCall] | None, str]:
        """ "while CONDITION (,) ACTION": the action until the condition no longer holds."""
        words = rest.split()
        for k in range(2, len(words) + 1):
            head, tail = " ".join(words[:k]), " ".join(words[k:])
            try:
                watch = watching.watch_of("while", head)
            except NotUnderstood:
                continue
            if not tail:
                continue
            try:
                steps, verb = self._clause(tail, label, notes, last_verb)
            except NotUnderstood:
                continue
            if not steps:
                continue
            if not phrases.LAPS.search(tail):
                steps = [_keep_going(s) for s in steps]
            return [_watched(s, watch) for s in steps], verb
        raise NotUnderstood(
            f"I do not plan around conditions ('while') such as '{rest}': I can go on while "
            "the battery is above a percent"
        )

    def _duration(self, rest: str, label: str, notes: list[str]) -> float | None:
        """Seconds named in `rest`; None if no time is given. Raises on words it cannot use."""
        seconds = 0.0
        found = False
        for tok in en.scan(rest):
            if tok.kind == "qty" and tok.unit in (nums.TIME, ""):
                if not tok.unit:
                    notes.append(f"no unit given for '{label}': took {tok.text} as seconds")
                seconds += tok.value
                found = True
            elif tok.kind == "qty":
                raise NotUnderstood("a wait takes a time such as '2 seconds'")
            elif tok.kind not in ("fill",) and tok.text not in vocab.WAIT_WORDS:
                raise NotUnderstood(f"I can only wait for a time, not '{tok.text}'")
        return seconds if found else None

    def _wait(self, text: str, label: str, notes: list[str]) -> list[SkillCall] | None:
        m = phrases.WAIT.match(text)
        if m is None:
            return None
        seconds = self._duration(m["rest"] or "", label, notes)
        if seconds is None:
            seconds = self.default_wait
            notes.append(f"no duration given for '{label}': waited {_fmt(seconds)} s")
        return [SkillCall("sys.wait", {"seconds": float(seconds)}, label)]

    def _posture(self, text: str, label: str, notes: list[str]) -> list[SkillCall] | None:
        m = phrases.POSTURE.match(text)
        if m is None:
            return None
        kind = next(k for k in ("lie", "sit", "stand") if m[k])
        steps = [SkillCall(vocab.POSTURE_SKILL[kind], {}, label)]
        # Words that only say where or how ("on the floor", "right here") change nothing.
        rest = canon(phrases.POSTURE_EXTRA.sub(" ", m["rest"] or ""))
        if rest:
            try:
                seconds = self._duration(rest, label, notes)
            except NotUnderstood:
                return None  # e.g. "stand on your front legs" is a trick, not a posture
            if seconds is not None:  # "sit for 10 seconds": sit, then stay so
                steps.append(SkillCall("sys.wait", {"seconds": float(seconds)}, label))
        return steps

    def _trick(self, text: str, label: str, notes: list[str]) -> list[SkillCall] | None:
        key = phrases.TRICK_PREFIX.sub("", text, count=1)
        key = canon(phrases.TRICK_STOPWORDS.sub(" ", key))
        key = phrases.TRICK_TAIL.sub("", key)
        own = {n.replace("_", " "): n for n in self.tricks or ()}  # a robot's own names
        trick = vocab.TRICK_NAMES.get(key) or vocab.TRICK_NAMES.get(canon(text)) or own.get(key)
        if trick is None and phrases.GREET.match(text) and self._offers("hello"):
            trick = "hello"
        if trick is None:
            return None
        if not self._offers(trick):
            offers = ", ".join(sorted(self.tricks or ())) or "none"
            raise NotUnderstood(
                f"this robot does not perform the {trick.replace('_', ' ')} trick (its tricks: "
                f"{offers})"
            )
        return [SkillCall("body.sport", {"trick": trick}, label)]

    def _offers(self, trick: str) -> bool:
        """The robot performs `trick` (any trick when the planner was not told its tricks)."""
        return self.tricks is None or trick in self.tricks

    def _goto(self, text: str, label: str, notes: list[str]) -> list[SkillCall] | None:
        m = phrases.GOTO.match(text)
        if m is None:
            return None
        target, back, prep = m["target"] or "", bool(m["back"]), bool(m["prep"])
        direct = bool(m["ret"]) or m["verb"] == "navigate"

        def goto(**args: Any) -> list[SkillCall]:
            return [SkillCall("nav.goto", args, label)]

        if not target:
            if m["ret"] == "return" or (back and not prep and m["verb"] != "move"):
                return goto(place="start")
            return None
        if phrases.HOME.match(target):
            return goto(place="home")
        nearby = target in ("here", "me", "us")  # only "come back here" says where to go
        if phrases.START.match(target) and (back or prep or direct) and (back or not nearby):
            return goto(place="start")
        if not (prep or direct):
            return None
        xy = phrases.COORDS.match(target)
        if xy is not None:
            x = en.quantity(xy["x"], xy["xu"])
            y = en.quantity(xy["y"], xy["yu"])
            if any(q.unit not in ("", nums.DISTANCE) for q in (x, y)):
                raise NotUnderstood("a position takes two distances, x and y")
            return goto(x=float(x.value), y=float(y.value))
        if phrases.POSITION_ONLY.match(target):
            raise NotUnderstood("a position needs two numbers, e.g. 'go to position 2, 1'")
        place = _thing(target, label, notes)
        return None if place is None else goto(place=place)

    def _face(self, text: str, label: str, notes: list[str]) -> list[SkillCall] | None:
        """ "face the blue box", "turn towards position 2, 1": turn in place to a thing, a
        place or a point (nav.face resolves the name as nav.goto does)."""
        m = phrases.FACE.match(text)
        if m is None:
            return None
        target = m["target"]
        xy = phrases.COORDS.match(target)
        if xy is not None:
            x, y = en.quantity(xy["x"], xy["xu"]), en.quantity(xy["y"], xy["yu"])
            if any(q.unit not in ("", nums.DISTANCE) for q in (x, y)):
                raise NotUnderstood("a position takes two distances, x and y")
            return [SkillCall("nav.face", {"x": float(x.value), "y": float(y.value)}, label)]
        if phrases.HOME.match(target):
            return [SkillCall("nav.face", {"place": "home"}, label)]
        thing = _thing(target, label, notes)
        if thing is None or set(thing.split()) & phrases.VIEW_WORDS:
            return None  # "turn to the left", "look at the view": not a thing to face
        return [SkillCall("nav.face", {"place": thing}, label)]

    def _find(self, text: str, label: str, notes: list[str]) -> list[SkillCall] | None:
        """ "find the blue box", "bring me to the fridge": go to a thing by name (nav.goto
        resolves it: a place, an object seen, else one to search for)."""
        m = phrases.FIND.match(text)
        if m is None:
            return None
        if phrases.HOME.match(m["target"]):
            return [SkillCall("nav.goto", {"place": "home"}, label)]
        if phrases.START.match(m["target"]) and m["target"] not in ("me", "us", "here"):
            return [SkillCall("nav.goto", {"place": "start"}, label)]
        place = _thing(m["target"], label, notes)
        if place is None:
            raise NotUnderstood("say which thing to find, e.g. 'find the red ball'")
        return [SkillCall("nav.goto", {"place": place}, label)]

    def _follow(self, text: str, label: str, notes: list[str]) -> list[SkillCall] | None:
        m = watching.FOLLOW.match(text)
        if m is None:
            return None
        args: dict[str, Any] = {"target": "person" if m["me"] else m["name"].strip()}
        if m["d"]:
            args["distance"] = float(m["d"])
        if m["t"]:
            args["seconds"] = float(m["t"]) * (60.0 if m["unit"].startswith("m") else 1.0)
        return [SkillCall("nav.follow", args, label)]

    def _patrol(self, text: str, label: str, notes: list[str]) -> list[SkillCall] | None:
        if not phrases.PATROL.search(text):
            return None
        laps: int | None = None if watching.KEEP_GOING.search(text) else 1
        m = phrases.LAPS.search(text)
        if m is not None:
            value = nums.to_float(m.group(1))
            if value != int(value) or value < 1:
                raise NotUnderstood("a patrol takes a whole number of laps")
            laps = int(value)
        return [SkillCall("nav.patrol", {"laps": laps}, label)]

    def _shape(self, text: str, label: str, notes: list[str]) -> list[SkillCall]:
        shape = phrases.SHAPE.search(text).group(1)  # type: ignore[union-attr]
        sign, speed = 1.0, None
        sides: list[en.Token] = []
        for tok in en.scan(text):
            if tok.kind == "qty":
                if tok.unit not in ("", nums.DISTANCE):
                    raise NotUnderstood(f"the sides of a {shape} are distances")
                sides.append(tok)
            elif tok.kind == "dir" and tok.text in ("right", "cw"):
                sign = -1.0
            elif tok.kind in ("speed", "adv"):
                speed = tok.value
            elif tok.kind == "word" and tok.text not in vocab.SHAPE_WORDS:
                raise NotUnderstood(f"I do not know '{tok.text}' in a shape")
        named = [t.unit_name for t in sides if t.unit_name]
        if len(named) < len(sides):
            unit = named[0] if named else None  # "2 by 1 meter": the unit covers both numbers
            if unit is None:
                notes.append(f"no unit given for '{label}': used metres")
            sides = [t if t.unit_name else en.quantity(t.text, unit) for t in sides]
        lengths = [t.value for t in sides]
        wanted = 2 if shape == "rectangle" else 1
        if not lengths:
            lengths = [self.default_square_side] * wanted
            notes.append(f"no side length given for '{label}': used {_fmt(lengths[0])} m")
        if len(set(lengths)) != wanted and not (wanted == 2 and len(lengths) == 2):
            raise NotUnderstood(
                "a rectangle needs two side lengths, e.g. '2 by 1 meter'"
                if wanted == 2
                else f"a {shape} has one side length"
            )
        n = vocab.SIDES[shape]
        turn = sign * 360.0 / n
        args: dict[str, Any] = {} if speed is None else {"speed": speed}
        steps = []
        for i in range(n):
            side = lengths[i % len(lengths)] if wanted == 2 else lengths[0]
            steps.append(SkillCall("nav.move", {"distance": float(side), **args}, label))
            steps.append(SkillCall("nav.rotate", {"degrees": turn}, label))
        return steps

    def _motion(
        self, verb: str, rest: str, label: str, notes: list[str], speed: float | None
    ) -> list[SkillCall]:
        kind, implied, verb_speed = vocab.VERBS[verb]
        speed = speed if speed is not None else verb_speed
        dirs = [implied] if implied else []
        qtys: list[en.Token] = []
        for tok in en.scan(rest):
            if tok.kind == "dir":
                dirs.append(tok.text)
            elif tok.kind == "qty":
                qtys.append(tok)
            elif tok.kind in ("speed", "adv"):
                speed = tok.value
            elif tok.kind == "word":
                raise NotUnderstood(f"'{tok.text}' does not fit a move or a turn")
        if kind == "rotate":
            return self._rotate(verb, dirs, qtys, label, notes)
        if verb == "come" and not dirs and not qtys:
            raise NotUnderstood("I do not know where you are; 'come back' returns to the start")
        if any(q.unit not in ("", nums.DISTANCE) for q in qtys):
            raise NotUnderstood("a move takes a distance, e.g. '2 meters'; use 'turn' to turn")
        if len(qtys) > 1 and any(not q.unit for q in qtys):
            raise NotUnderstood("I found more than one number for one move")
        if any(d in ("cw", "ccw", "around") for d in dirs):
            raise NotUnderstood("to change heading, say 'turn left' or 'turn around'")
        forward = {1 if d == "forward" else -1 for d in dirs if d in ("forward", "back")}
        lateral = {1 if d == "left" else -1 for d in dirs if d in ("left", "right")}
        if len(forward) > 1 or len(lateral) > 1 or (forward and (lateral or "side" in dirs)):
            raise NotUnderstood("the directions contradict each other; give one per step")
        if qtys:
            distance = round(sum(q.value for q in qtys), 9)  # "5 feet 6 inches" without noise
            if not qtys[0].unit:
                notes.append(f"no unit given for '{label}': took {qtys[0].text} as metres")
        else:
            distance = self.default_distance
            notes.append(f"no distance given for '{label}': used {_fmt(distance)} m")
        args: dict[str, Any] = {} if speed is None else {"speed": speed}
        if "backforth" in dirs:
            return [
                SkillCall("nav.move", {"distance": float(distance), **args}, label),
                SkillCall("nav.move", {"distance": -float(distance), **args}, label),
            ]
        if lateral or "side" in dirs or (kind == "strafe" and not forward):
            if not lateral:
                notes.append(f"no side given for '{label}': stepped left")
            sign = lateral.pop() if lateral else 1
            return [SkillCall("nav.strafe", {"distance": float(sign * distance), **args}, label)]
        if not forward:
            notes.append(f"no direction given for '{label}': moved forward")
        sign = forward.pop() if forward else 1
        return [SkillCall("nav.move", {"distance": float(sign * distance), **args}, label)]

    def _rotate(
        self, verb: str, dirs: list[str], qtys: list[en.Token], label: str, notes: list[str]
    ) -> list[SkillCall]:
        signs = set()
        around = False
        for d in dirs:
            if d in ("left", "ccw"):
                signs.add(1.0)
            elif d in ("right", "cw"):
                signs.add(-1.0)
            elif d in ("around", "back"):
                around = True
            else:
                raise NotUnderstood(f"a turn goes left or right, not {d}")
        if len(signs) > 1:
            raise NotUnderstood("the directions contradict each other; give one per turn")
        if any(q.unit not in ("", nums.ANGLE) for q in qtys):
            raise NotUnderstood("a turn takes an angle such as '90 degrees', not a distance")
        if len(qtys) > 1 and any(not q.unit for q in qtys):
            raise NotUnderstood("I found more than one number for one turn")
        if qtys:
            degrees = round(sum(q.value for q in qtys), 9)
            if not qtys[0].unit:
                notes.append(f"no unit given for '{label}': took {qtys[0].text} as degrees")
        elif around and verb != "spin":
            degrees = 180.0
        elif verb == "spin":  # a spin is a full circle, "spin around" included
            degrees = 360.0
            notes.append(f"no angle given for '{label}': spun a full circle")
        else:
            degrees = self.default_turn_degrees
            notes.append(f"no angle given for '{label}': turned {_fmt(degrees)} degrees")
        if not signs and (qtys or not around):
            notes.append(f"no direction given for '{label}': turned counter-clockwise (left)")
        sign = signs.pop() if signs else 1.0
        return [SkillCall("nav.rotate", {"degrees": float(sign * degrees)}, label)]


def _answers(step: SkillCall) -> bool:
    """Whether a step's output answers the user (its skill declares `reports`)."""
    return step.skill in _reporting()


@cache
def _reporting() -> frozenset[str]:
    return frozenset(s.name for s in default_registry() if s.reports)


def _implied_verb(text: str, last_verb: str) -> str:
    """The verb a verbless clause borrows: "turn left 90 then right 45", "2 meters forward"."""
    tokens = en.scan(text)
    if not tokens or tokens[0].kind not in ("dir", "qty"):
        return ""
    units = {t.unit for t in tokens if t.kind == "qty"}
    rotating = bool(last_verb) and vocab.VERBS[last_verb][0] == "rotate"
    if nums.ANGLE in units:
        return last_verb if rotating else "turn"
    if nums.DISTANCE in units and (rotating or not last_verb):
        return "move"
    return last_verb if tokens[0].kind == "dir" or last_verb else ""


def _thing(target: str, label: str, notes: list[str]) -> str | None:
    """The name of a place or thing in a go-to or find ("the red ball" -> "red ball"), or None
    when the words cannot name one (a direction, a distance, more than five words)."""
    words = canon(phrases.ARTICLES.sub(" ", target)).split()
    while words and words[-1] in vocab.ADVERBS:
        notes.append(f"'{words.pop()}' ignored in '{label}': go-to uses its own speed")
    place = " ".join(words)
    if not phrases.PLACE.match(place) or len(words) > 5 or place in phrases.NOT_PLACES:
        return None
    if any(q.group(2) for q in nums.QTY.finditer(place)):
        return None  # "go to the left 2 meters" is a move
    return place


def _check_size(steps: list[SkillCall], size: int) -> None:
    if size > MAX_STEPS:
        raise PlanningError(
            f"The plan would have {size} steps; the limit is {MAX_STEPS}. Ask for fewer repeats.",
            understood=[describe(s) for s in steps[:20]],
        )


def _watched(step: SkillCall, watch: Watch) -> SkillCall:
    """`step` also watching `watch`."""
    return replace(step, watches=(*step.watches, watch))


def _when_branch(norm: str) -> re.Match[str] | None:
    """ "when the battery is below 20% go to the dock": a branch, as "if" is, when what
    follows "when" begins with a condition the robot can watch."""
    m = watching.WHEN.match(norm)
    return m if m and next(watching.split_condition(m["rest"]), None) else None


def _guarded(step: SkillCall, guard: Watch | None) -> SkillCall:
    """`step` run only if `guard` holds (or does not: an "otherwise"); `step` without one."""
    return step if guard is None else replace(step, guard=guard)


def _last_branch(steps: list[SkillCall]) -> int:
    return max((s.guard.branch for s in steps if s.guard is not None), default=0)


def _repeated(steps: list[SkillCall], times: int) -> list[SkillCall]:
    """`steps` `times` over ("repeat that"): each time's branches are branches of their own,
    decided when that time reaches them."""
    last = _last_branch(steps)
    return [
        s
        if s.guard is None or not s.guard.branch
        else replace(s, guard=replace(s.guard, branch=s.guard.branch + k * last))
        for k in range(times)
        for s in steps
    ]


def _keep_going(step: SkillCall) -> SkillCall:
    """A patrol that goes on lap after lap (as the mission's limits allow) until its watch
    ends it; any other step as it is."""
    if step.skill == "nav.patrol" and step.args.get("laps") == 1:
        return replace(step, args={**step.args, "laps": None})
    return step
