"""JSON routes: missions, e-stop, approvals, chat, status, diagnostics, skills, map.

Routes are thin: they validate, call the agent's public API or the mission desk, and shape the
answer. Fast calls (status, e-stop) run in the event loop so nothing queues in front of them;
chat may wait on a language model, so it runs in a worker thread.
"""

from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Annotated, Any

from fastapi import APIRouter, Body, HTTPException, Query, Request
from fastapi.responses import Response

from .. import __version__
from ..admission import ESTOP_LATCHED, mission_text_problem
from ..agent import RobotAgent
from ..memory.places import known_places
from ..skills.context import robot_belief, robot_objects
from ..worker import TELEOP_BUSY
from .desk import MissionDesk, WebMission
from .estop import stopped_already
from .feed import EventFeed
from .frames import FrameCache
from .models import (
    ChatAnswer,
    ChatRequest,
    EstopAnswer,
    MissionAccepted,
    MissionRefused,
    MissionRequest,
    Problem,
    RejectRequest,
)
from .responses import StrictJSON
from .worldmap import GridImages, grid_layout, grid_version, object_dicts


@dataclass
class WebContext:
    """What the routes share; kept on `app.state.web`."""

    agent: RobotAgent
    desk: MissionDesk
    feed: EventFeed
    frames: FrameCache
    auth: bool


def ctx(request: Request) -> WebContext:
    context: WebContext = request.app.state.web
    return context


router = APIRouter(prefix="/api")
# Each route's own error answers; the gate's (400, 401, 403, 413) and 422 are added to the
# document by openapi.py.
_NOT_FOUND: dict[int | str, dict[str, Any]] = {
    404: {"model": Problem, "description": "no such mission or approval"}
}
_REFUSED: dict[int | str, dict[str, Any]] = {
    409: {"model": MissionRefused, "description": "the e-stop is latched (dry runs still run)"},
    429: {"model": MissionRefused, "description": "the queue is full"},
}
_CANCEL: dict[int | str, dict[str, Any]] = {
    **_NOT_FOUND,
    409: {"model": Problem, "description": "the mission has already finished"},
}


@router.get("/health", tags=["status"])
async def health(request: Request) -> dict[str, Any]:
    """Liveness; open even when a token is set (the original answer plus a few keys)."""
    agent = ctx(request).agent
    return {
        "status": "healthy",
        "service": "shadowhound-web",
        "version": __version__,
        "estop": agent.estop_latched,
    }


@router.post(
    "/mission",
    status_code=202,
    response_model=MissionAccepted,
    responses=_REFUSED,
    tags=["missions"],
)
async def submit_mission(request: Request, body: MissionRequest) -> MissionAccepted | StrictJSON:
    """Queue a mission (or a dry run). 202 with its id; follow it on /ws/status or /api/events."""
    web = ctx(request)
    problem = mission_text_problem(
        body.command, web.agent.settings.agent.max_mission_chars, "the command"
    )
    if problem:
        raise HTTPException(422, problem)
    ahead = web.desk.queued() + (1 if web.desk.worker.busy else 0)
    record, refused = web.desk.submit(body.command, body.dry_run)
    if record is None:
        status = 409 if refused in (ESTOP_LATCHED, TELEOP_BUSY) else 429
        return StrictJSON(
            {
                "detail": refused,
                "success": False,
                "message": f"Refused: {refused}.",
                "command": body.command,
            },
            status_code=status,
        )
    what = "dry run" if body.dry_run else "mission"
    where = "starts now" if not ahead else f"waits behind {ahead} mission(s)"
    return MissionAccepted(
        success=True,
        message=f"{what} accepted; it {where}",
        command=body.command,
        mission_id=record.id,
        state=record.state,
        dry_run=body.dry_run,
        queued_ahead=ahead,
        url=f"/api/missions/{record.id}",
    )


@router.get("/missions", tags=["missions"])
async def list_missions(request: Request, limit: int = Query(50, ge=1, le=500)) -> dict[str, Any]:
    """Recent missions, newest first (web missions, then other interfaces' from the agent)."""
    return {"missions": ctx(request).desk.missions(limit)}


def _record(request: Request, mission_id: str) -> WebMission:
    record = ctx(request).desk.get(mission_id)
    if record is None:
        raise HTTPException(
            404, f"no mission {mission_id!r} (the dashboard keeps the last 200 web missions)"
        )
    return record


@router.get("/missions/{mission_id}", responses=_NOT_FOUND, tags=["missions"])
async def get_mission(request: Request, mission_id: str) -> dict[str, Any]:
    """One mission: its state and, once finished, the full result with every step."""
    return _record(request, mission_id).to_dict()


@router.post("/missions/{mission_id}/cancel", responses=_CANCEL, tags=["missions"])
async def cancel_mission(request: Request, mission_id: str) -> dict[str, Any]:
    """Cancel a waiting or running mission; a running one stops within one control tick."""
    record, outcome = ctx(request).desk.cancel(mission_id)
    if record is None:
        raise HTTPException(404, f"no mission {mission_id!r}")
    if outcome == "finished":
        raise HTTPException(
            409, f"mission {mission_id!r} has already finished ({record.to_dict(False)['status']})"
        )
    return {"mission_id": record.id, "cancelled": True, "state": record.state}


@router.post("/estop", response_model=EstopAnswer, tags=["safety"])
async def estop(request: Request) -> EstopAnswer:
    """Emergency stop: the robot stops before this answers; latched until released."""
    web = ctx(request)
    dropped = stopped_already(request.state)  # the e-stop lane stopped it before routing
    if dropped is None:
        dropped = web.desk.estop()
    return EstopAnswer(
        estop=True,
        dropped=dropped,
        robot=web.agent.get_robot_status(),
        message="e-stop latched: the robot is stopped"
        + (f" and {dropped} waiting mission(s) dropped" if dropped else "")
        + "; release it to run missions again",
    )


@router.post("/estop/release", response_model=EstopAnswer, tags=["safety"])
async def release_estop(request: Request) -> EstopAnswer:
    agent = ctx(request).agent
    agent.release_estop()
    return EstopAnswer(
        estop=agent.estop_latched, message="e-stop released", robot=agent.get_robot_status()
    )


@router.get("/approval", tags=["safety"])
async def pending_approval(request: Request) -> dict[str, Any]:
    """The plan waiting for a person's approval, if any."""
    return {"pending": ctx(request).agent.pending_approval()}


@router.post("/approval/{request_id}/approve", responses=_NOT_FOUND, tags=["safety"])
async def approve(request: Request, request_id: str) -> dict[str, Any]:
    if not ctx(request).agent.approve(request_id):
        raise HTTPException(404, f"no pending approval {request_id!r}")
    return {"request_id": request_id, "approved": True}


@router.post("/approval/{request_id}/reject", responses=_NOT_FOUND, tags=["safety"])
async def reject(
    request: Request, request_id: str, body: Annotated[RejectRequest | None, Body()] = None
) -> dict[str, Any]:
    reason = body.reason if body else ""
    if not ctx(request).agent.reject(request_id, reason or "rejected on the dashboard"):
        raise HTTPException(404, f"no pending approval {request_id!r}")
    return {"request_id": request_id, "approved": False}


@router.post("/chat", response_model=ChatAnswer, tags=["chat"])
def chat(request: Request, body: ChatRequest) -> ChatAnswer:
    """Ask about the robot and its missions; never moves the robot."""
    agent = ctx(request).agent
    text = body.text[: agent.settings.agent.max_mission_chars]
    try:
        answer = agent.chat(text)
    except Exception as exc:  # a model or network failure is an answer, not a 500
        answer = f"Sorry, I could not answer: {exc}"
    return ChatAnswer(question=text, answer=answer)


@router.get("/status", tags=["status"])
async def status(request: Request) -> dict[str, Any]:
    """What the robot and the mission are doing now (small and fast; polled by dashboards)."""
    return current_status(ctx(request))


def current_status(web: WebContext) -> dict[str, Any]:
    d = web.agent.diagnostics()
    running = web.desk.running()
    return {
        **d.progress.to_dict(),
        "estop": d.estop,
        "busy": web.desk.worker.busy,
        "teleop": web.desk.worker.teleop.on,
        "running": running.id if running else None,
        "queued": web.desk.queued(),
        "pending_approval": d.pending_approval.to_dict() if d.pending_approval else None,
        "robot": d.robot_dict(),
        "time": time.time(),
    }


@router.get("/diagnostics", tags=["status"])
async def diagnostics(request: Request) -> dict[str, Any]:
    """The agent's diagnostics, the original dashboard's keys, and the web server's own."""
    web = ctx(request)
    d = web.agent.diagnostics().to_dict()
    settings = web.agent.settings
    d.update(
        agent_backend=settings.backend,
        agent_model=settings.llm.model or "offline",
        robot_name=web.agent.robot.name,
        robot_description=web.agent.robot.description,
        robot_mode=d["robot"].get("posture"),
        last_update=time.time(),
        web={
            "clients": web.feed.clients,
            "busy": web.desk.worker.busy,
            "queued": web.desk.queued(),
            "auth": web.auth,
            "approvals_enabled": web.agent.approvals_enabled,
        },
    )
    return d


@router.get("/skills", tags=["status"])
async def skills(request: Request) -> dict[str, Any]:
    """Every skill with its argument schema (the registry is the one source of truth)."""
    return {"skills": ctx(request).agent.get_available_skills()}


_GRID_IMAGES = GridImages()


@router.get("/map", tags=["status"])
async def world_map(request: Request) -> dict[str, Any]:
    """What the dashboard's map draws besides the robot: places, route, geofence, the known
    objects, the names a labelled map gives its obstacles (`labels`: the simulator's scene,
    known before anything is seen) and the occupancy grid's layout and version (its image:
    /api/map/grid.png)."""
    agent = ctx(request).agent
    settings, robot = agent.settings, agent.robot
    places = known_places(settings.places, agent.memory.places)  # taught ones too
    belief = robot_belief(robot)
    grid = None if belief is None else grid_layout(belief.grid, grid_version(belief.grid))
    return {
        "grid": grid,
        "objects": object_dicts(robot_objects(robot)),
        "labels": object_dicts(belief.labels if belief is not None else ()),
        "places": {name: list(place.position) for name, place in places.items()},
        "patrol_route": [list(p) for p in settings.patrol_route],
        "geofence_radius": settings.safety.geofence_radius,
        "geofence_polygon": [list(p) for p in settings.safety.geofence_polygon or []],
        "robot": ctx(request).agent.get_robot_status(),
    }


@router.get(
    "/map/grid.png",
    tags=["status"],
    response_class=Response,
    responses={200: {"content": {"image/png": {}}}, 404: {"model": Problem}},
)
async def grid_image(request: Request) -> Response:
    """The occupancy grid as a grayscale PNG (free white, occupied black, unknown grey), its
    top row the largest y; place it with /api/map's `grid` layout. Cached by version."""
    belief = robot_belief(ctx(request).agent.robot)
    if belief is None:
        raise HTTPException(
            404,
            "this robot has no map (the simulator with collisions off, or "
            "a robot without a map source)",
        )
    version = grid_version(belief.grid)
    etag = f'"{version}"'
    headers = {"ETag": etag, "Cache-Control": "no-cache"}
    if request.headers.get("if-none-match") == etag:
        return Response(status_code=304, headers=headers)
    return Response(_GRID_IMAGES.png(belief.grid, version), media_type="image/png", headers=headers)
