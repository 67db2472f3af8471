"""The MCP desk: what MCP tools do, as plain Python over `RobotAgent` and `MissionWorker`.

No MCP SDK here: `server.py` turns tool calls into these methods and their answers into MCP
results. Missions and single skill calls both run on the one mission worker, and only when it
is idle (`start_now`): a second run is refused with `BUSY`, never queued to start by surprise.
A skill call is a one-step plan (`RobotAgent.run_plan`), so it passes the same validation, the
same governor and the same approvals as a planned step. Releasing the e-stop is a person's
decision: the desk does it only when built with `allow_release_estop`, and the server asks the
person before every release.
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any

from ..admission import ESTOP_LATCHED, mission_text_problem
from ..agent import RobotAgent
from ..camera import encode_jpeg
from ..errors import ToolInputError
from ..events import MissionEvent
from ..memory.places import known_places
from ..plan import SkillCall
from ..skills import SkillValidationError
from ..worker import MissionJob, MissionWorker

BUSY = "busy: another mission is running; wait for it to finish or call cancel_mission"
IMAGE_MAX_SIDE = 512  # pixels: enough to see, small enough for a client model's context
IMAGE_QUALITY = 75

OnEvent = Callable[[MissionEvent], None]
OnDone = Callable[[MissionJob], None]


@dataclass(frozen=True)
class CameraImage:
    """A JPEG for an MCP image content block."""

    data: bytes
    width: int
    height: int
    stamp: float
    source: str


class McpDesk:
    """Runs MCP clients' missions and skill calls on the agent, one at a time.

    `worker` may be shared with another interface in the same process (the web desk, the ROS
    node); then the one-mission rule holds across all of them. Without one, the desk makes its
    own (and stops it on `close`). `allow_release_estop` lets MCP clients release the e-stop,
    each time with a person's approval (off: only a person, elsewhere, can release it).
    """

    def __init__(
        self,
        agent: RobotAgent,
        *,
        worker: MissionWorker | None = None,
        allow_release_estop: bool = False,
    ) -> None:
        self.agent = agent
        self.allow_release_estop = allow_release_estop
        self._own_worker = worker is None
        self.worker = worker or MissionWorker(agent)
        # Risky calls ask the person through the client (elicitation); the server answers
        # every approval request, refusing it where the client cannot ask.
        agent.enable_approvals()

    # -- missions ------------------------------------------------------------------------------

    def start_mission(
        self,
        text: Any,
        dry_run: Any = False,
        on_event: OnEvent | None = None,
        on_done: OnDone | None = None,
    ) -> MissionJob:
        """Accept a mission now or raise ToolInputError (bad text, busy, e-stop latched).

        `on_event` sees the mission's events on the mission thread; `on_done` runs there too,
        once the job's result (or why it never ran) is set (on the cancelling thread for a job
        cancelled before it started).
        """
        text = self._mission_text(text)
        if not isinstance(dry_run, bool):
            raise ToolInputError(f"dry_run must be true or false, got {dry_run!r}")
        return self._start(
            MissionJob(text, source="mcp", dry_run=dry_run, on_event=on_event, on_done=on_done)
        )

    def start_skill(
        self,
        skill: str,
        arguments: Any,
        on_event: OnEvent | None = None,
        on_done: OnDone | None = None,
    ) -> MissionJob:
        """Accept one skill call as a one-step plan. Raises ToolInputError for bad arguments."""
        if arguments is None:
            arguments = {}
        if not isinstance(arguments, dict):
            raise ToolInputError(
                f"{skill}: arguments must be an object, got {type(arguments).__name__}"
            )
        _check_finite(skill, arguments)
        try:  # early, for a clear answer; run_plan validates again, with the governor
            valid = self.agent.registry.validate(SkillCall(skill, dict(arguments)))
        except SkillValidationError as exc:
            raise ToolInputError("; ".join(exc.problems)) from exc
        call = SkillCall(valid.name, dict(arguments), label="mcp")  # as given: run_plan checks
        shown = ", ".join(f"{k}={v!r}" for k, v in valid.args_dict().items())
        return self._start(
            MissionJob(
                f"{valid.name}({shown})",
                source="mcp",
                calls=[call],
                on_event=on_event,
                on_done=on_done,
            )
        )

    def _start(self, job: MissionJob) -> MissionJob:
        if self.agent.estop_latched and not job.dry_run:
            raise ToolInputError(ESTOP_LATCHED)
        if self.worker.start_now(job) is not None:  # its only refusal: not idle
            raise ToolInputError(BUSY)
        return job

    def abandon(self, job: MissionJob) -> None:
        """The client went away (or cancelled the call): stop this job if it still runs."""
        if not job.done.is_set():
            self.worker.cancel(job.mission_id)  # the robot stops within one control tick

    def plan(self, text: Any) -> dict[str, Any]:
        """The dry run: steps, predicted path and refusals; nothing moves."""
        return self.agent.dry_run(self._mission_text(text)).to_dict()

    def _mission_text(self, text: Any) -> str:
        problem = mission_text_problem(text, self.agent.settings.agent.max_mission_chars, "text")
        if problem:
            raise ToolInputError(problem)
        return str(text)

    # -- stopping --------------------------------------------------------------------------

    def estop(self) -> dict[str, Any]:
        """Stop the robot at once and latch; waiting missions are dropped."""
        dropped = len(self.worker.estop())  # the robot stops first, then the queue is dropped
        return {
            "estop_latched": True,
            "dropped": dropped,
            "robot": self.agent.get_robot_status(),  # read after the stop
            "response": "e-stop latched: the robot is stopped and stays stopped until a "
            "person releases the e-stop",
        }

    def release_estop(self) -> dict[str, Any]:
        """Release the latch: call only with a person's approval (the server asks first).
        Raises ToolInputError when the desk was not built with `allow_release_estop`."""
        if not self.allow_release_estop:
            raise ToolInputError(
                "the e-stop stays latched: this server lets no MCP client release it; "
                "a person must release it"
            )
        self.agent.release_estop()
        return {"estop_latched": False, "response": "e-stop released by the person"}

    def cancel(self) -> dict[str, Any]:
        """Cancel the running mission (whichever interface started it)."""
        job = self.worker.current
        if job is None and not self.worker.busy:
            return {"cancelled": False, "response": "no mission is running"}
        if job is not None:
            self.worker.cancel(job.mission_id)
        return {
            "cancelled": True,
            "mission_id": job.mission_id if job else None,
            "response": "mission cancelled; the robot is stopped",
        }

    # -- information -------------------------------------------------------------------------

    def state(self) -> dict[str, Any]:
        status = self.agent.get_robot_status()
        current = self.worker.current
        return {
            "robot": status,
            "estop_latched": self.agent.estop_latched,
            "busy": self.worker.busy,
            "mission": None
            if current is None
            else {"mission_id": current.mission_id, "text": current.command},
        }

    def camera_image(self, max_side: int = IMAGE_MAX_SIDE) -> CameraImage:
        """The latest camera frame as a downscaled JPEG. Raises ToolInputError without one."""
        frame = self.agent.latest_frame()
        if frame is None:
            raise ToolInputError("no camera frame yet")
        try:
            data = encode_jpeg(frame, max_side=max_side, quality=IMAGE_QUALITY)
        except ImportError as exc:
            raise ToolInputError("images need Pillow: pip install 'shadowhound[mcp]'") from exc
        except ValueError as exc:
            raise ToolInputError(str(exc)) from exc
        scale = min(1.0, max_side / max(frame.width, frame.height, 1))
        return CameraImage(
            data, round(frame.width * scale), round(frame.height * scale), frame.stamp, frame.source
        )

    def history(self, limit: Any = 10) -> list[dict[str, Any]]:
        if isinstance(limit, bool) or not isinstance(limit, int) or not 1 <= limit <= 100:
            raise ToolInputError(f"limit must be a whole number from 1 to 100, got {limit!r}")
        return self.agent.recent_missions(limit)

    def last_mission(self) -> dict[str, Any] | None:
        history = self.agent.history
        return history[-1].to_dict() if history else None

    def places(self) -> dict[str, dict[str, float]]:
        """Places from the profile, then taught ones (which win)."""
        known = known_places(self.agent.settings.places, self.agent.memory.places)
        return {
            n: {"x": p.x, "y": p.y, **({} if p.yaw is None else {"yaw": p.yaw})}
            for n, p in known.items()
        }

    def close(self) -> None:
        """Stop any mission and, if the worker is the desk's own, end it."""
        self.agent.cancel()
        if self._own_worker:
            self.worker.stop()


def _check_finite(skill: str, arguments: dict[str, Any]) -> None:
    """JSON from some clients carries NaN or Infinity; no skill argument may be either."""
    for name, value in arguments.items():
        if isinstance(value, float) and not math.isfinite(value):
            raise ToolInputError(f"{skill}: {name!r} must be a finite number, got {value}")
