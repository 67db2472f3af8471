"""The MCP server: tools, resources and a prompt over `McpDesk`, on the SDK's low-level Server.

Only this package imports the MCP SDK. Every tool call ends in an MCP answer: a result, a
result with `isError` (bad arguments, busy, refused by the governor: the message says what
was wrong and what is allowed), or a protocol error for an unknown tool. A call the client
abandons (cancelled, or the client went away) stops its mission and the robot.

Long because: the MCP surface is one table of tools, resources and a prompt, each a few lines
mapping the SDK's request onto one `McpDesk` call; splitting them would scatter that table.
"""

from __future__ import annotations

import asyncio
import base64
import logging
import secrets
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
from .catalogue import ToolSpec, all_tools
from .desk import McpDesk

log = logging.getLogger(__name__)

SERVER_NAME = "shadowhound"
INSTRUCTIONS = (
    "Drives a quadruped robot. Every motion passes a safety governor; risky ones "
    "ask the person. Prefer run_mission for whole tasks; call emergency_stop if "
    "anything looks wrong."
)
RESOURCES = {
    "shadowhound://skills": ("skills", "The skill catalogue with argument schemas."),
    "shadowhound://places": ("places", "Known places (profile and taught), odom frame."),
    "shadowhound://missions/last": ("last-mission", "The last mission's full record."),
}
MISSION_PROMPT = "mission"
_APPROVE_SCHEMA: dict[str, Any] = {
    "type": "object",
    "properties": {
        "approve": {"type": "boolean", "title": "Approve", "description": "let the robot do this"}
    },
    "required": ["approve"],
}

_APPROVAL_KEY = "approval"

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


class McpRobotServer:
    """Builds the SDK `Server` for one agent. `server` is what a transport runs."""

    def __init__(self, agent: RobotAgent, desk: McpDesk | None = None) -> None:
        self.agent = agent
        self.desk = desk or McpDesk(agent)
        self.tools = all_tools(agent.registry, agent.settings.agent.max_mission_chars)
        self._by_name = {t.name: t for t in self.tools}
        self._waiting: dict[str, _Watch] = {}  # request_state -> a job waiting for approval
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
            _check_args(spec, args)
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
            "release_estop": desk.release_estop,
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
        """Ask the person through the client (elicitation); refuse where it cannot ask.

        Over a connection with a back-channel (handshake-era stdio and HTTP sessions) the
        question is sent at once. Without one (the 2026-07-28 protocol) the call answers
        `InputRequiredResult` and the mission waits for the client to call again with the
        person's answer (`_resume`), within safety.approval_timeout.
        """
        request_id = request["request_id"]
        caps = ctx.session.client_capabilities
        if caps is None or caps.elicitation is None:
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
        if not ctx.session.can_send_request:
            state = secrets.token_urlsafe(16)
            watch.request_id = request_id
            self._waiting = {
                k: w
                for k, w in self._waiting.items()
                if w.job is not None and not w.job.done.is_set()
            }
            self._waiting[state] = watch
            return types.InputRequiredResult(
                input_requests={
                    _APPROVAL_KEY: types.ElicitRequest(
                        params=types.ElicitRequestFormParams(
                            message=message, requested_schema=_APPROVE_SCHEMA
                        )
                    )
                },
                request_state=state,
            )
        try:
            answer = await asyncio.wait_for(
                ctx.session.elicit_form(
                    message, _APPROVE_SCHEMA, related_request_id=ctx.request_id
                ),
                timeout=request["timeout"],
            )
        except (MCPError, asyncio.TimeoutError) as exc:
            self.agent.reject(request_id, f"the client could not ask: {exc}")
            return None
        self._decide(request_id, answer)
        return None

    async def _resume(
        self, ctx: ServerRequestContext[Any], params: types.CallToolRequestParams
    ) -> ToolAnswer:
        """A call made again with the person's answer to `InputRequiredResult`."""
        watch = self._waiting.pop(params.request_state or "", None)
        if watch is None or watch.job is None or watch.job.done.is_set():
            return _error(
                "no approval is pending for this call (it was answered, timed out "
                "or never asked); call the tool again"
            )
        answer = (params.input_responses or {}).get(_APPROVAL_KEY)
        if not isinstance(answer, types.ElicitResult):
            self.agent.reject(watch.request_id, "the client sent no answer to the approval")
        else:
            self._decide(watch.request_id, answer)
        return await self._follow(ctx, watch)

    def _decide(self, request_id: str, answer: types.ElicitResult) -> None:
        content = answer.content or {}
        if answer.action == "accept" and content.get("approve") is True:
            self.agent.approve(request_id)
        else:
            how = "declined" if answer.action != "accept" else "not approved"
            self.agent.reject(request_id, f"{how} by the person (MCP elicitation)")

    # -- resources and the prompt --------------------------------------------------------------

    async def _list_resources(
        self, _ctx: ServerRequestContext[Any], _params: types.PaginatedRequestParams | None
    ) -> types.ListResourcesResult:
        return types.ListResourcesResult(
            resources=[
                types.Resource(uri=uri, name=name, description=text, mime_type="application/json")
                for uri, (name, text) in RESOURCES.items()
            ]
        )

    async def _read_resource(
        self, _ctx: ServerRequestContext[Any], params: types.ReadResourceRequestParams
    ) -> types.ReadResourceResult:
        uri = str(params.uri)
        readers: dict[str, Callable[[], Any]] = {
            "shadowhound://skills": self.agent.get_available_skills,
            "shadowhound://places": self.desk.places,
            "shadowhound://missions/last": self.desk.last_mission,
        }
        if uri not in readers:
            raise MCPError(
                types.INVALID_PARAMS,
                f"unknown resource {uri[:200]!r}; known: " + ", ".join(RESOURCES),
            )
        data = await asyncio.to_thread(readers[uri])
        return types.ReadResourceResult(
            contents=[
                types.TextResourceContents(
                    uri=uri, mime_type="application/json", text=jsonout.dumps(data)
                )
            ]
        )

    async def _list_prompts(
        self, _ctx: ServerRequestContext[Any], _params: types.PaginatedRequestParams | None
    ) -> types.ListPromptsResult:
        return types.ListPromptsResult(
            prompts=[
                types.Prompt(
                    name=MISSION_PROMPT,
                    description="Ask the robot to do something, checked first.",
                    arguments=[
                        types.PromptArgument(
                            name="task", required=True, description="what the robot should do"
                        )
                    ],
                )
            ]
        )

    async def _get_prompt(
        self, _ctx: ServerRequestContext[Any], params: types.GetPromptRequestParams
    ) -> types.GetPromptResult:
        if params.name != MISSION_PROMPT:
            raise MCPError(
                types.INVALID_PARAMS, f"unknown prompt {params.name!r}; known: {MISSION_PROMPT}"
            )
        task = (params.arguments or {}).get("task", "").strip()
        if not task:
            raise MCPError(types.INVALID_PARAMS, "the mission prompt needs a 'task'")
        text = (
            f"Have the robot do this: {task}\n"
            "First call plan_mission with that sentence and read the plan and any refusals. "
            "If the plan is right, call run_mission with the same sentence and report what "
            "happened from its result. If anything looks unsafe, call emergency_stop."
        )
        return types.GetPromptResult(
            messages=[
                types.PromptMessage(role="user", content=types.TextContent(type="text", text=text))
            ]
        )


def _tool(spec: ToolSpec) -> types.Tool:
    return types.Tool(
        name=spec.name,
        description=spec.description,
        input_schema=spec.input_schema,
        annotations=types.ToolAnnotations(read_only_hint=True) if spec.read_only else None,
    )


def _check_args(spec: ToolSpec, args: Any) -> None:
    """The schema's rules for the few non-skill tools, each said in a sentence."""
    if not isinstance(args, dict):
        raise ToolInputError(f"{spec.name}: arguments must be an object")
    props = spec.input_schema.get("properties", {})
    unknown = sorted(set(args) - set(props))
    if unknown:
        raise ToolInputError(
            f"{spec.name}: unknown argument(s) {', '.join(unknown)}; allowed: "
            + (", ".join(props) or "none")
        )
    for name in spec.input_schema.get("required", []):
        if name not in args:
            raise ToolInputError(f"{spec.name}: missing required argument {name!r}")
    for name, value in args.items():
        kind = props[name].get("type")
        ok = {
            "string": isinstance(value, str),
            "boolean": isinstance(value, bool),
            "integer": isinstance(value, int) and not isinstance(value, bool),
        }.get(kind, True)
        if not ok:
            raise ToolInputError(
                f"{spec.name}: {name!r} must be a {kind}, got "
                f"{type(value).__name__} {str(value)[:40]!r}"
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
