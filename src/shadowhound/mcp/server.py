"""The MCP server: tools over `McpDesk`, on the SDK's low-level Server (the resources and the
prompt are in `resources.py`; the questions for the person in `person.py`).

Only this package imports the MCP SDK. Every tool call ends in an MCP answer: a result, a
result with `isError` (bad arguments, busy, refused by the governor: the message says what
was wrong and what is allowed), or a protocol error for an unknown tool. A call the client
abandons (cancelled, or the client went away) stops its mission and the robot. Releasing the
e-stop is a person's decision: the `release_estop` tool exists only when the server is built to
offer it, and then every call asks the person through the client first.
"""

from __future__ import annotations

import asyncio
import base64
import logging
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

import mcp_types as types
from mcp.server import Server, ServerRequestContext
from mcp.shared.exceptions import MCPError

from .. import __version__, jsonout
from .. import events as ev
from ..agent import RobotAgent
from ..errors import ToolInputError
from ..result import StepStatus
from ..worker import MissionJob
from . import person, resources
from .catalogue import ToolSpec, all_tools
from .desk import McpDesk

log = logging.getLogger(__name__)

SERVER_NAME = "shadowhound"
INSTRUCTIONS = (
    "Drives a quadruped robot. Every motion passes a safety governor; risky ones "
    "ask the person. Prefer run_mission for whole tasks; call emergency_stop if "
    "anything looks wrong: the robot then stays stopped until a person releases it."
)
_RELEASE_QUESTION = (
    "ShadowHound: an MCP client asks to release the e-stop. The robot is stopped now; once "
    "released, missions can move it again. Release the e-stop?"
)
_LATCHED_STAYS = "the e-stop stays latched"

_Start = Callable[[Callable[[ev.MissionEvent], None], Callable[[MissionJob], None]], MissionJob]
ToolAnswer = types.CallToolResult | types.InputRequiredResult


@dataclass(eq=False)
class _Watch:
    """A job an MCP call follows: its events (None when done), the plan's size, and the
    approval it waits for while the client asks the person."""

    events: asyncio.Queue[ev.MissionEvent | None]
    job: MissionJob | None = None
    total: int = 0
    request_id: str = ""

    def pending(self) -> bool:
        return self.job is not None and not self.job.done.is_set()


@dataclass(eq=False)
class _Release:
    """A release of the e-stop waiting for the person's answer (until `deadline`, monotonic)."""

    deadline: float

    def pending(self) -> bool:
        return time.monotonic() < self.deadline


class McpRobotServer:
    """Builds the SDK `Server` for one agent. `server` is what a transport runs."""

    def __init__(
        self, agent: RobotAgent, desk: McpDesk | None = None, *, allow_release_estop: bool = False
    ) -> None:
        """`allow_release_estop` offers the `release_estop` tool (each call asks the person);
        it builds the desk when none is given. A given desk brings its own setting."""
        self.agent = agent
        self.desk = desk or McpDesk(agent, allow_release_estop=allow_release_estop)
        self.tools = all_tools(
            agent.registry,
            agent.settings.agent.max_mission_chars,
            release_estop=self.desk.allow_release_estop,
        )
        self._by_name = {t.name: t for t in self.tools}
        # Asked without a back-channel: a job's approval or a release, until the answer comes.
        self._questions: person.Questions[_Watch | _Release] = person.Questions()
        self.server: Server[Any] = Server(
            SERVER_NAME,
            version=__version__,
            instructions=INSTRUCTIONS,
            on_list_tools=self._list_tools,
            on_call_tool=self._call_tool,
            on_list_resources=self._list_resources,
            on_read_resource=self._read_resource,
            on_list_prompts=self._list_prompts,
            on_get_prompt=self._get_prompt,
        )

    def close(self) -> None:
        self.desk.close()

    # -- tools ---------------------------------------------------------------------------------

    async def _list_tools(
        self, _ctx: ServerRequestContext[Any], _params: types.PaginatedRequestParams | None
    ) -> types.ListToolsResult:
        return types.ListToolsResult(tools=[_tool(t) for t in self.tools])

    async def _call_tool(
        self, ctx: ServerRequestContext[Any], params: types.CallToolRequestParams
    ) -> ToolAnswer:
        if params.request_state is not None:
            return await self._resume(ctx, params)
        spec = self._by_name.get(params.name)
        if spec is None:
            raise MCPError(
                types.INVALID_PARAMS,
                f"unknown tool {params.name!r}; call tools/list for the available tools",
            )
        args = params.arguments or {}
        try:
            if spec.skill is not None:
                return await self._run(
                    ctx,
                    lambda on_event, on_done: self.desk.start_skill(
                        spec.name, args, on_event, on_done
                    ),
                )
            spec.check_args(args)
            return await self._simple(ctx, spec.name, args)
        except ToolInputError as exc:
            return _error(str(exc))
        except Exception as exc:  # a bug or a robot fault: an answer, never a dead server
            log.exception("MCP tool %s failed", params.name)
            return _error(f"internal error in {params.name}: {exc!r}")

    async def _simple(
        self, ctx: ServerRequestContext[Any], name: str, args: dict[str, Any]
    ) -> ToolAnswer:
        desk = self.desk
        if name == "run_mission":
            dry = args.get("dry_run", False)
            return await self._run(
                ctx,
                lambda on_event, on_done: desk.start_mission(
                    args.get("text"), dry, on_event, on_done
                ),
            )
        if name == "plan_mission":
            text = args.get("text")
            return _answer(await asyncio.to_thread(desk.plan, text), ok_key="success")
        if name == "release_estop":
            return await self._release_estop(ctx)
        if name == "get_camera_image":
            image = await asyncio.to_thread(desk.camera_image)
            meta = {
                "width": image.width,
                "height": image.height,
                "stamp": image.stamp,
                "source": image.source,
            }
            return types.CallToolResult(
                content=[
                    types.ImageContent(
                        type="image",
                        data=base64.b64encode(image.data).decode(),
                        mime_type="image/jpeg",
                    ),
                    types.TextContent(type="text", text=jsonout.dumps(meta)),
                ],
                structured_content=meta,
            )
        actions: dict[str, Callable[[], Any]] = {
            "get_state": desk.state,
            "emergency_stop": desk.estop,
            "cancel_mission": desk.cancel,
            "history": lambda: {"missions": desk.history(args.get("limit", 10))},
        }
        # The e-stop runs right here, not on a thread: nothing may queue in front of it.
        data = (
            actions[name]() if name == "emergency_stop" else await asyncio.to_thread(actions[name])
        )
        return _answer(data)

    async def _run(self, ctx: ServerRequestContext[Any], start: _Start) -> ToolAnswer:
        """Start a job and follow it to its result."""
        loop = asyncio.get_running_loop()
        watch = _Watch(asyncio.Queue())

        def on_event(event: ev.MissionEvent) -> None:  # on the mission thread
            loop.call_soon_threadsafe(watch.events.put_nowait, event)

        def on_done(_job: MissionJob) -> None:
            loop.call_soon_threadsafe(watch.events.put_nowait, None)

        watch.job = start(on_event, on_done)
        return await self._follow(ctx, watch)

    async def _follow(self, ctx: ServerRequestContext[Any], watch: _Watch) -> ToolAnswer:
        """Report the job's steps as progress and answer approvals until its result."""
        job = watch.job
        assert job is not None
        try:
            while (event := await watch.events.get()) is not None:
                if isinstance(event, ev.ApprovalRequired):
                    asked = await self._ask_approval(ctx, event.request.to_dict(), watch)
                    if asked is not None:  # the client asks the person and calls again
                        return asked
                else:
                    await self._report(ctx, event, watch)
        except BaseException:  # cancelled, or the client went away: stop the robot
            self.desk.abandon(job)
            raise
        if job.result is None:
            return _error(f"the mission did not run: {job.dropped or 'unknown reason'}")
        return _answer(job.result.to_dict(), ok_key="success")

    async def _report(
        self, ctx: ServerRequestContext[Any], event: ev.MissionEvent, watch: _Watch
    ) -> None:
        total = watch.total or None
        if isinstance(event, ev.PlanReady):
            watch.total = len(event.plan.steps)
            await ctx.session.report_progress(0, watch.total, f"plan: {watch.total} step(s)")
        elif isinstance(event, ev.StepStarted):
            step = event.step
            args = ", ".join(f"{k}={v}" for k, v in step.args.items())
            await ctx.session.report_progress(
                step.index - 1, total, f"[{step.index}] {step.skill}({args})"
            )
        elif isinstance(event, ev.StepFinished):
            step = event.step
            ok = step.status is StepStatus.SUCCEEDED
            await ctx.session.report_progress(
                step.index,
                total,
                f"[{step.index}] {step.status.value}: {step.output if ok else step.error}",
            )

    async def _ask_approval(
        self, ctx: ServerRequestContext[Any], request: dict[str, Any], watch: _Watch
    ) -> types.InputRequiredResult | None:
        """Ask the person through the client; refuse where it cannot ask (`person.py`). Without
        a back-channel the call answers `InputRequiredResult` and the mission waits for the
        client to call again with the answer (`_resume`), within safety.approval_timeout."""
        request_id = request["request_id"]
        if not person.can_ask(ctx):
            self.agent.reject(
                request_id,
                "this MCP client cannot ask a person (it does not "
                "support elicitation), so calls that need approval are refused",
            )
            return None
        message = (
            "ShadowHound asks for approval: "
            + "; ".join(request["reasons"])
            + f". Mission: {request['mission']!r}"
        )
        if not person.can_ask_now(ctx):
            watch.request_id = request_id
            return self._questions.ask_later(watch, message, person.APPROVE_SCHEMA)
        try:
            answer = await person.ask_now(ctx, message, person.APPROVE_SCHEMA, request["timeout"])
        except (MCPError, asyncio.TimeoutError) as exc:
            self.agent.reject(request_id, f"the client could not ask: {exc}")
            return None
        self._decide(request_id, answer)
        return None

    async def _resume(
        self, ctx: ServerRequestContext[Any], params: types.CallToolRequestParams
    ) -> ToolAnswer:
        """A call made again with the person's answer to `InputRequiredResult`."""
        taken = self._questions.take(params)
        if taken is None:
            return _error(
                "no approval is pending for this call (it was answered, timed out "
                "or never asked); call the tool again"
            )
        waiting, answer = taken
        if isinstance(waiting, _Release):
            return await self._release_if_agreed(answer)
        if not isinstance(answer, types.ElicitResult):
            self.agent.reject(waiting.request_id, "the client sent no answer to the approval")
        else:
            self._decide(waiting.request_id, answer)
        return await self._follow(ctx, waiting)

    def _decide(self, request_id: str, answer: types.ElicitResult) -> None:
        if person.said_yes(answer, "approve"):
            self.agent.approve(request_id)
        else:
            how = "declined" if answer.action != "accept" else "not approved"
            self.agent.reject(request_id, f"{how} by the person (MCP elicitation)")

    # -- the e-stop's release ------------------------------------------------------------------

    async def _release_estop(self, ctx: ServerRequestContext[Any]) -> ToolAnswer:
        """Release the e-stop only when a person agrees, asked through the client."""
        if not self.agent.estop_latched:
            return _answer({"estop_latched": False, "response": "the e-stop is not latched"})
        if not person.can_ask(ctx):
            return _error(
                f"{_LATCHED_STAYS}: only a person may release it, and this MCP client cannot "
                "ask one (it does not support elicitation)"
            )
        timeout = self.agent.settings.safety.approval_timeout
        if not person.can_ask_now(ctx):
            release = _Release(time.monotonic() + timeout)
            return self._questions.ask_later(release, _RELEASE_QUESTION, person.RELEASE_SCHEMA)
        try:
            answer = await person.ask_now(ctx, _RELEASE_QUESTION, person.RELEASE_SCHEMA, timeout)
        except (MCPError, asyncio.TimeoutError) as exc:
            return _error(f"{_LATCHED_STAYS}: the person could not be asked ({exc!r})")
        return await self._release_if_agreed(answer)

    async def _release_if_agreed(self, answer: Any) -> ToolAnswer:
        if not person.said_yes(answer, "release"):
            return _error(f"{_LATCHED_STAYS}: the person did not agree to release it")
        return _answer(await asyncio.to_thread(self.desk.release_estop))

    # -- resources and the prompt (resources.py) -----------------------------------------------

    async def _list_resources(
        self, _ctx: ServerRequestContext[Any], _params: types.PaginatedRequestParams | None
    ) -> types.ListResourcesResult:
        return resources.resource_list()

    async def _read_resource(
        self, _ctx: ServerRequestContext[Any], params: types.ReadResourceRequestParams
    ) -> types.ReadResourceResult:
        return await asyncio.to_thread(resources.read_resource, self.desk, str(params.uri))

    async def _list_prompts(
        self, _ctx: ServerRequestContext[Any], _params: types.PaginatedRequestParams | None
    ) -> types.ListPromptsResult:
        return resources.prompt_list()

    async def _get_prompt(
        self, _ctx: ServerRequestContext[Any], params: types.GetPromptRequestParams
    ) -> types.GetPromptResult:
        return resources.get_prompt(params.name, params.arguments)


def _tool(spec: ToolSpec) -> types.Tool:
    return types.Tool(
        name=spec.name,
        description=spec.description,
        input_schema=spec.input_schema,
        annotations=types.ToolAnnotations(read_only_hint=True) if spec.read_only else None,
    )


def _answer(data: Any, ok_key: str | None = None) -> types.CallToolResult:
    structured = data if isinstance(data, dict) else {"value": data}
    failed = ok_key is not None and not structured.get(ok_key, False)
    return types.CallToolResult(
        content=[types.TextContent(type="text", text=jsonout.dumps(structured))],
        structured_content=structured,
        is_error=failed,
    )


def _error(message: str) -> types.CallToolResult:
    return types.CallToolResult(
        content=[types.TextContent(type="text", text=message)], is_error=True
    )
