"""LLMPlanner: plans with a language model behind an OpenAI-compatible server.

plan mode (default): one request returns the whole plan, as JSON constrained by a schema
(`plan_format` json_schema) or as parallel tool calls (`tools`). Every call is validated
against the registry; if any is invalid the model gets one repair round trip that says exactly
what was wrong. Safety refusals are never "repaired": a limit is not negotiable. The model may
refuse a request instead (`{"refusal": "why"}`): the mission fails with its reason, and no
step of that reply runs.

react mode: a bounded tool-calling loop. The model calls one skill, the agent validates,
checks and runs it, the result goes back, and so on until the model answers in words, the step
limit or the token budget is reached, or the mission is cancelled.

A request that states a condition ("until you see the ball", "unless someone is in the way")
is refused unless the plan expresses it (`conditions.unhonoured`): never planned as if the
condition were not there. A JSON plan carries them (`conditions`, schema.py and parse.py);
tool calls (tools and react mode) cannot, so there such a request is refused before the model
is asked.
"""

from __future__ import annotations

import json
import logging
from typing import Any

from ..config import ShadowHoundConfig
from ..errors import BackendError
from ..llm.backend import LLMBackend, request_hints
from ..plan import Plan, PlanningError, SkillCall, Usage, oversize
from ..skills import SkillValidationError
from . import PlanningContext, StepRunner, conditions, prompts, schema
from .parse import ParsedReply, parse_reply

log = logging.getLogger(__name__)


class LLMPlanner:
    """A planner that asks a language model. Build it with the settings of one backend."""

    kind = "llm"
    needs_context = True

    def __init__(self, settings: ShadowHoundConfig, backend: LLMBackend | None = None) -> None:
        self.settings = settings
        self.llm = settings.llm
        # The model's client: given by the agent (one for planning, chat, vision, memory).
        self.backend = backend or LLMBackend(settings.backend, settings.llm)
        self.name = f"{settings.backend}:{settings.llm.model}"
        self._schema_ok = True  # cleared when the server rejects response_format

    # -- plan mode -----------------------------------------------------------------------------

    def plan(self, text: str, context: Any = None) -> Plan:
        return self._plan(text, text, context)

    def replan(self, text: str, context: Any, done: list[str], failure: str) -> Plan:
        """A new plan for the rest of the mission after a step failed."""
        situation = (
            f"Original request: {text}\nDone so far: {'; '.join(done) or 'nothing'}\n"
            f"A step failed: {failure}\nPlan only the remaining steps from the robot's current "
            "state, or refuse, saying why, if the request cannot be finished."
        )
        return self._plan(text, situation, context)

    def _plan(self, text: str, prompt: str, context: Any) -> Plan:
        """Plan the request `text`, asking the model with `prompt`."""
        style = "tools" if self._format() == "tools" else "plan"
        if style == "tools":
            _refuse_unhonoured(text, None, Usage())  # tool calls cannot say one: do not ask
        ctx = _context(context)
        usage = Usage()
        messages = [
            {"role": "system", "content": self._system(ctx, style)},
            {"role": "user", "content": prompt},
        ]
        for attempt in range(self.llm.repair_attempts + 1):
            reply, raw = self._ask(messages, style, ctx, usage)
            if reply.refusal:
                raise _refused(reply.refusal, usage)
            calls, problems = self._checked(reply, ctx)
            if not problems and calls:
                plan = Plan(
                    calls,
                    text=text,
                    usage=usage,
                    planner=self.name,
                    planned_by="llm",
                    notes=[reply.answer] if reply.answer else [],
                )
                _refuse_unhonoured(text, plan, usage)
                return plan
            if not problems:  # no steps: the model says why in words
                raise PlanningError(reply.answer or "The model proposed no steps.", usage=usage)
            usage.invalid_plans += 1
            if attempt < self.llm.repair_attempts:
                messages += [raw, {"role": "user", "content": _repair_request(problems, style)}]
        raise PlanningError(
            "The model's plan was not valid after a repair attempt: " + "; ".join(problems),
            not_understood=problems,
            usage=usage,
        )

    def _format(self) -> str:
        fmt = self.llm.plan_format
        if fmt == "auto":
            return "json_schema" if self._schema_ok else "plain"
        return fmt if fmt != "json_schema" or self._schema_ok else "plain"

    def _ask(
        self, messages: list[dict[str, Any]], style: str, ctx: PlanningContext, usage: Usage
    ) -> tuple[ParsedReply, dict[str, Any]]:
        options: dict[str, Any] = {}
        fmt = self._format()
        if style == "tools":
            options["tools"] = self._tools(ctx)
            if self.settings.backend == "openai":
                options["parallel_tool_calls"] = True
        elif fmt == "json_schema":
            options["response_format"] = schema.response_format(
                self.settings.backend, ctx.registry, self.llm.plan_schema
            )
        try:
            completion = self._complete(messages, usage, ctx, **options)
        except BackendError as exc:
            # Servers say "not supported" in different ways: 400/422, or a 500 naming the field.
            rejected = exc.status in (400, 422) or (
                exc.status == 500 and "response_format" in str(exc)
            )
            if not rejected or "response_format" not in options:
                raise PlanningError(str(exc), usage=usage) from exc
            log.warning("server rejected response_format json_schema; asking without it")
            self._schema_ok = False
            options.pop("response_format")
            if messages and messages[0].get("role") == "system":  # it may have named the schema
                messages[0] = {"role": "system", "content": self._system(ctx, style)}
            try:
                completion = self._complete(messages, usage, ctx, **options)
            except BackendError as again:
                raise PlanningError(str(again), usage=usage) from again
        message = completion.message
        raw = {"role": "assistant", "content": message.get("content") or ""}
        if message.get("tool_calls"):
            raw["tool_calls"] = message["tool_calls"]
        return parse_reply(message, self.llm.max_reply_depth), raw

    def _complete(
        self, messages: list[dict[str, Any]], usage: Usage, ctx: PlanningContext, **options: Any
    ) -> Any:
        if ctx.cancelled is not None and ctx.cancelled.is_set():
            raise PlanningError("mission cancelled before the model was asked", usage=usage)
        hints = request_hints(self.settings.backend)
        try:  # a cancel ends the wait at once (BackendCancelled) and nothing more is sent
            completion = self.backend.complete(
                messages, cancelled=ctx.cancelled, **options, extra_body=hints or None
            )
        except BackendError:
            usage.round_trips += 1  # a failed request is still a round trip
            raise
        except RecursionError as exc:  # the client's JSON decoder gave up on the body
            usage.round_trips += 1
            raise PlanningError(
                "the model's server sent an answer nested too deep to read "
                f"(a reply may nest at most {self.llm.max_reply_depth} deep, "
                "llm.max_reply_depth)",
                usage=usage,
            ) from exc
        usage.add(completion.usage)
        return completion

    def _checked(
        self, reply: ParsedReply, ctx: PlanningContext
    ) -> tuple[list[SkillCall], list[str]]:
        """Validate every proposed call; canonical names and parsed arguments on success. A
        reply larger than one plan may be is refused whole, no call of it validated."""
        too_big = oversize(reply.calls, self.settings.agent)
        if too_big:  # the size first: the rest of such a reply is not worth reading
            return [], too_big
        problems = list(reply.problems)
        calls = []
        for index, call in enumerate(reply.calls, start=1):
            try:
                valid = ctx.registry.validate(schema.without_unset(ctx.registry, call))
            except SkillValidationError as exc:
                problems += [f"step {index}: {p}" for p in exc.problems]
                continue
            calls.append(
                SkillCall(valid.name, valid.args_dict(), call.label, valid.watches, valid.guard)
            )
        return calls, problems

    def _tools(self, ctx: PlanningContext) -> list[dict[str, Any]]:
        if self.settings.backend == "openai":  # the one API that enforces `strict` tools
            return schema.strict_tools(ctx.registry)
        return prompts.tools(ctx.registry)

    def _system(self, ctx: PlanningContext, style: str) -> str:
        if (
            style == "plan"
            and self._format() == "json_schema"
            and schema.dialect_of(self.settings.backend) == "openai"
        ):
            style = "plan_schema"  # OpenAI shows the model the schema: the prompt need not
        return prompts.system_prompt(
            ctx.registry,
            style=style,
            state=ctx.state,
            places=ctx.places,
            history=ctx.history,
            history_size=self.settings.agent.conversation_history_size,
            memories=ctx.memories,
            objects=ctx.objects,
        )


def _refused(reason: str, usage: Usage) -> PlanningError:
    return PlanningError(f"The model refused to plan this request: {reason}", usage=usage)


def _refuse_unhonoured(text: str, plan: Plan | None, usage: Usage) -> None:
    """Raise the refusal when `text` states a condition that `plan` does not express (None: no
    plan can, so any condition)."""
    missing = conditions.unhonoured(text, plan)
    if missing:
        raise conditions.refusal(missing, usage)


def _context(context: Any) -> PlanningContext:
    if isinstance(context, PlanningContext):
        return context
    from ..skills import default_registry

    return PlanningContext(registry=default_registry())


def _repair_request(problems: list[str], style: str) -> str:
    how = "Call the tools again" if style in ("tools", "react") else "Reply with the JSON plan"
    return (
        "Your plan cannot be used: "
        + "; ".join(problems)
        + f". {how}, corrected, and nothing else."
    )


def _assistant_turn(message: dict[str, Any], reply: ParsedReply) -> dict[str, Any]:
    if reply.used_tools:
        return {
            "role": "assistant",
            "content": message.get("content") or "",
            "tool_calls": message["tool_calls"],
        }
    return {
        "role": "assistant",
        "content": json.dumps({"steps": [{"skill": c.skill, "args": c.args} for c in reply.calls]}),
    }


def _observation(call: SkillCall, call_id: str | None, observation: str) -> dict[str, Any]:
    if call_id is not None:
        return {"role": "tool", "tool_call_id": call_id, "content": observation}
    return {"role": "user", "content": f"Result of {call.skill}: {observation}"}


class ReactPlanner(LLMPlanner):
    """react mode: the model calls one skill at a time and sees what it did."""

    def react(self, text: str, context: Any, run_step: StepRunner) -> tuple[str, Usage, bool]:
        """Run the tool loop. Returns (answer for the user, usage, finished normally)."""
        _refuse_unhonoured(text, None, Usage())  # calls proposed one by one carry no watch
        ctx = _context(context)
        usage = Usage()
        messages: list[dict[str, Any]] = [
            {"role": "system", "content": self._system(ctx, "react")},
            {"role": "user", "content": text},
        ]
        tools = self._tools(ctx)
        executed = 0
        while True:
            if usage.total_tokens >= self.llm.react_token_budget:
                return (
                    f"Stopped: the token budget of {self.llm.react_token_budget} "
                    "(llm.react_token_budget) is used up.",
                    usage,
                    False,
                )
            try:
                completion = self._complete(messages, usage, ctx, tools=tools)
            except BackendError as exc:
                raise PlanningError(str(exc), usage=usage) from exc
            reply = parse_reply(completion.message, self.llm.max_reply_depth)
            if reply.refusal:
                raise _refused(reply.refusal, usage)
            if not reply.calls and completion.finish_reason == "length":
                return (
                    f"Stopped: the model's answer was cut off at {self.llm.max_tokens} "
                    "tokens (llm.max_tokens).",
                    usage,
                    False,
                )
            if reply.problems and not reply.calls:
                messages += [
                    {"role": "assistant", "content": completion.message.get("content") or ""},
                    {"role": "user", "content": _repair_request(reply.problems, "react")},
                ]
                continue
            if not reply.calls:
                return reply.answer or "Done.", usage, True
            messages.append(_assistant_turn(completion.message, reply))
            for call, call_id in zip(reply.calls, reply.call_ids, strict=True):
                if executed >= self.llm.react_max_steps:
                    return (
                        f"Stopped after {executed} skill calls (llm.react_max_steps).",
                        usage,
                        False,
                    )
                observation = run_step(call)
                executed += 1
                messages.append(_observation(call, call_id, observation))
