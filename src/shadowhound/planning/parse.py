"""The model planner's reading of replies: plans out of what models really send.

Tool calls, a JSON plan in the content, JSON in ``` fences, <tool_call> tags, a bare list of
steps, arguments as JSON strings: all become SkillCalls, and anything unusable becomes a problem
sentence that goes back to the model. A refusal (a `refuse` step with its reason, as the plan
schema offers it, a `{"refusal": "why"}` object, or the `refusal` of an OpenAI message) is the
model's decision: its reason, cleaned and cut short, and no steps, whatever else the reply
holds. Arguments are passed on as the model wrote them: the
registry reads numbers with units ("3cm", "90 deg") the same way for every caller, and decides
with the safety governor whether a call is valid.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass, field, replace
from typing import Any

from ..config import LLMConfig
from ..plan import GUARD_WHEN, WATCH_KINDS, WATCH_WHEN, SkillCall, Watch, with_branches
from .schema import ANSWER_MAX_CHARS, REFUSE

MAX_DEPTH: int = LLMConfig.model_fields["max_reply_depth"].default  # one default: the setting's

_THINK = re.compile(r"<think>.*?</think>", re.DOTALL | re.IGNORECASE)
_FENCE = re.compile(r"```(?:json|JSON)?\s*(.*?)```", re.DOTALL)
_TOOL_TAG = re.compile(r"<tool_call>\s*(.*?)\s*</tool_call>", re.DOTALL)
_CONTROL = re.compile(r"[\x00-\x1f\x7f-\x9f\u200b-\u200f\u2028-\u202e\u2066-\u2069]")


@dataclass
class ParsedReply:
    """What a model reply proposes: calls (with tool-call ids when it used tools), a text answer,
    and problems that make (part of) it unusable."""

    calls: list[SkillCall] = field(default_factory=list)
    call_ids: list[str | None] = field(default_factory=list)
    answer: str = ""
    problems: list[str] = field(default_factory=list)
    used_tools: bool = False
    refusal: str = ""  # the model's reason for refusing the request; then no calls


def parse_reply(message: dict[str, Any], max_depth: int = MAX_DEPTH) -> ParsedReply:
    """What `message` (an OpenAI chat message) proposes. JSON nested deeper than `max_depth`
    (`llm.max_reply_depth`) is not read: it is a problem sentence, whatever else it holds."""
    reply = _parse(message, max_depth)
    native = message.get("refusal")  # OpenAI's own: the model declined
    if isinstance(native, str) and native.strip():
        reply.refusal = native
    if not reply.refusal:
        return reply
    reason = clean_reason(reply.refusal)
    reason = "no reason given" if reason in ("", "none") else reason
    return ParsedReply(refusal=reason, used_tools=reply.used_tools)


def clean_reason(text: str) -> str:
    """A model's words as one short line for people: no control or bidi characters, no
    quotes around it, spaces collapsed, at most `ANSWER_MAX_CHARS` characters."""
    words = " ".join(_CONTROL.sub(" ", text).split()).strip("\"'` ")
    if len(words) > ANSWER_MAX_CHARS:
        words = words[: ANSWER_MAX_CHARS - 3].rstrip() + "..."
    return words


def nesting(text: str) -> int:
    """How deep the JSON in `text` nests: its deepest run of open [ and { outside strings,
    counted in one pass (no recursion, so a reply of any depth is measured, never decoded)."""
    depth = deepest = 0
    in_string = escaped = False
    for ch in text:
        if in_string:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == '"':
                in_string = False
        elif ch == '"':
            in_string = True
        elif ch in "[{":
            depth += 1
            deepest = max(deepest, depth)
        elif ch in "]}":
            depth = max(0, depth - 1)
    return deepest


def too_deep(text: str, max_depth: int) -> str:
    """The problem with JSON `text` nested deeper than `max_depth`; "" when it is not."""
    depth = nesting(text)
    if depth <= max_depth:
        return ""
    return f"the model's reply nests {depth} deep; at most {max_depth} (llm.max_reply_depth)"


def _parse(message: dict[str, Any], max_depth: int) -> ParsedReply:
    reply = ParsedReply()
    for i, call in enumerate(message.get("tool_calls") or [], start=1):
        function = call.get("function") or {}
        arguments = function.get("arguments")
        if isinstance(arguments, str) and (deep := too_deep(arguments, max_depth)):
            reply.problems.append(f"tool call {i}: {deep}")
        else:
            _add(reply, function.get("name"), arguments, f"tool call {i}", call.get("id"))
        reply.used_tools = True
    content = message.get("content") or ""
    if isinstance(content, list):  # content parts
        content = " ".join(p.get("text", "") for p in content if isinstance(p, dict))
    content = _THINK.sub("", str(content)).strip()
    if reply.used_tools or not content:
        reply.answer = content
        return reply
    found = _json_values(content, max_depth, reply.problems)
    if reply.problems:
        return reply
    if not found:
        reply.answer = content
        return reply
    for value in found:
        _interpret(reply, value)
    return reply


def _json_values(content: str, max_depth: int, problems: list[str]) -> list[Any]:
    """JSON values in tags, fences, or the text itself (the first parseable one). A source
    nested deeper than `max_depth` is not decoded: `problems` says so."""
    tagged = _TOOL_TAG.findall(content)
    sources = tagged or _FENCE.findall(content) or [content]
    values = []
    decoder = json.JSONDecoder()
    for source in sources:
        text = source.strip()
        if deep := too_deep(text, max_depth):
            problems.append(deep)
            continue
        for start in (i for i, ch in enumerate(text) if ch in "[{"):
            try:
                value, _end = decoder.raw_decode(text, start)
            except RecursionError:  # measured shallow, yet too deep for the decoder
                problems.append(f"the model's reply nests too deep to read; at most {max_depth}")
                break
            except ValueError:
                continue
            values.append(value)
            break
    return values


def _interpret(reply: ParsedReply, value: Any) -> None:
    if isinstance(value, list):
        for item in value:
            _step(reply, item, f"step {len(reply.calls) + 1}")
        return
    if not isinstance(value, dict):
        reply.problems.append(f"expected a JSON object with 'steps', got {type(value).__name__}")
        return
    if isinstance(value.get("refusal"), str) and value["refusal"].strip():
        reply.refusal = value["refusal"]
        return
    if isinstance(value.get("answer"), str) and value["answer"].strip():
        reply.answer = value["answer"].strip()
    for key in ("steps", "plan", "tool_calls", "calls", "actions"):
        if key in value:
            steps = value[key]
            if not isinstance(steps, list):
                reply.problems.append(
                    f"'{key}' must be a list of steps, got {type(steps).__name__}"
                )
                return
            for item in steps:
                _step(reply, item, f"step {len(reply.calls) + 1}")
            _conditions(reply, value.get("conditions"))
            reply.calls = with_branches(reply.calls)  # an "if" and its "otherwise": one branch
            return
    if any(k in value for k in ("skill", "name", "function", "tool")):
        _step(reply, value, f"step {len(reply.calls) + 1}")
    elif not reply.answer:
        reply.problems.append(
            'the JSON has no \'steps\' list; expected {"steps": [{"skill": ..., "args": {...}}]}'
        )


def _step(reply: ParsedReply, item: Any, where: str) -> None:
    if not isinstance(item, dict):
        reply.problems.append(
            f"{where} must be an object with 'skill' and 'args', got {json.dumps(item)[:80]}"
        )
        return
    function: dict[str, Any] = item["function"] if isinstance(item.get("function"), dict) else {}
    name = item.get("skill") or item.get("name") or item.get("tool") or function.get("name")
    if name is None and isinstance(item.get("function"), str):
        name = item["function"]
    args = next(
        (item[k] for k in ("args", "arguments", "parameters", "params", "input") if k in item),
        function.get("arguments", function.get("parameters", {})),
    )
    _add(reply, name, args, where, None)


def _add(reply: ParsedReply, name: Any, args: Any, where: str, call_id: str | None) -> None:
    if not isinstance(name, str) or not name.strip():
        reply.problems.append(f"{where} has no skill name")
        return
    if isinstance(args, str):
        try:
            args = json.loads(args) if args.strip() else {}
        except RecursionError:
            reply.problems.append(f"{where} ({name}): its arguments nest too deep to read")
            return
        except ValueError:
            reply.problems.append(f"{where} ({name}): arguments are not valid JSON: {args[:80]!r}")
            return
    if args is None:
        args = {}
    if name.strip() == REFUSE:
        reason = args.get("reason") if isinstance(args, dict) else None
        reply.refusal = reply.refusal or (reason if isinstance(reason, str) else "") or "none"
        return
    if not isinstance(args, dict):
        reply.problems.append(
            f"{where} ({name}): arguments must be an object, got {json.dumps(args)[:80]}"
        )
        return
    reply.calls.append(SkillCall(name.strip(), args))
    reply.call_ids.append(call_id)


_WHEN = (*WATCH_WHEN, *GUARD_WHEN)


def _conditions(reply: ParsedReply, given: Any) -> None:
    """The plan's `conditions`, each onto its step: a watch (until, unless) or the step's guard
    (if, if_not). Whether the robot can observe one is checking's to say; a condition that
    cannot be read is a problem sentence for the model, never dropped."""
    if given is None or given == []:
        return
    if not isinstance(given, list):
        reply.problems.append(f"'conditions' must be a list, got {type(given).__name__}")
        return
    watched: dict[int, list[Watch]] = {}
    for n, item in enumerate(given, start=1):
        where = f"condition {n}"
        if not isinstance(item, dict):
            reply.problems.append(f"{where} must be an object, got {json.dumps(item)[:80]}")
            continue
        step = item.get("step")
        if isinstance(step, bool) or not isinstance(step, int) or not 1 <= step <= len(reply.calls):
            reply.problems.append(
                f"{where}: 'step' must be the number of one of the {len(reply.calls)} steps "
                f"(1 to {len(reply.calls)}), got {step!r}"
            )
            continue
        when, kind = item.get("when"), item.get("kind")
        if when not in _WHEN or kind not in WATCH_KINDS:
            reply.problems.append(
                f"{where}: 'when' is one of {', '.join(_WHEN)} and 'kind' one of "
                f"{', '.join(WATCH_KINDS)}; got {when!r}, {kind!r}"
            )
            continue
        numbers = {k: item.get(k) for k in ("within", "percent")}
        bad = [
            k
            for k, v in numbers.items()
            if v is not None and (isinstance(v, bool) or not isinstance(v, (int, float)))
        ]
        name = item.get("name")
        if bad or (name is not None and not isinstance(name, str)):
            reply.problems.append(
                f"{where}: 'within' and 'percent' are numbers and 'name' text, got "
                f"{json.dumps(item)[:120]}"
            )
            continue
        watch = Watch(
            when,
            kind,
            name=(name or "").strip(),
            within=None if numbers["within"] is None else float(numbers["within"]),
            percent=None if numbers["percent"] is None else float(numbers["percent"]),
        )
        at = reply.calls[step - 1]
        if when in GUARD_WHEN:
            if at.guard is not None:
                reply.problems.append(f"{where}: step {step} already has an 'if'")
                continue
            reply.calls[step - 1] = replace(at, guard=watch)
        else:  # added once per step below: a step's tuple is not copied per condition
            watched.setdefault(step - 1, []).append(watch)
    for index, more in watched.items():
        at = reply.calls[index]
        reply.calls[index] = replace(at, watches=(*at.watches, *more))
