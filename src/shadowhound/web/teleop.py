"""Driving from the page (issue 27): `POST /api/teleop` switches the pad on or off,
`POST /api/teleop/drive` sends its deflection, numbered (`seq`: a late request is dropped).
Everything it commands passes the agent's teleoperation limits (`shadowhound.teleop`: the
governor's rules for nav.move, nav.strafe and nav.rotate, speed caps, acceleration, geofence,
obstacles on the map, a dead-man of 0.35 s, an idle switch-off); the worker refuses it during a
mission and a latched e-stop."""

from __future__ import annotations

from typing import Any

from fastapi import APIRouter, Request

from ..teleop import HEARTBEAT
from .api import ctx
from .models import Problem, TeleopDrive, TeleopSwitch
from .responses import StrictJSON

router = APIRouter(prefix="/api")


def _state(request: Request, dropped: str = "") -> dict[str, Any]:
    web = ctx(request)
    teleop = web.desk.worker.teleop
    lim = web.agent.settings.safety
    last = teleop.last
    return {
        "on": teleop.on,
        "heartbeat": HEARTBEAT,
        "stop_after": round(teleop.stop_after, 3),
        # From the speed cap to a standstill, braking at the command cap (the simulated Go2's).
        "braking": round(lim.max_linear_speed / lim.max_linear_accel, 2),
        "idle_timeout": teleop.idle_timeout,
        "ended": teleop.ended,
        "max_linear_speed": lim.max_linear_speed,
        "max_angular_speed": lim.max_angular_speed,
        "sent": {"vx": last.vx, "vy": last.vy, "wz": last.wz},
        "limited": last.limited,
        "dropped": dropped,
    }


@router.get("/teleop", tags=["teleop"])
async def teleop_state(request: Request) -> dict[str, Any]:
    """Whether the pad drives, its timings and speed caps, why it last switched itself off,
    and what was sent to the robot last."""
    return _state(request)


_OFF: dict[int | str, dict[str, Any]] = {
    409: {"model": Problem, "description": "driving is off, or cannot be switched on (why)"}
}


@router.post("/teleop", responses=_OFF, tags=["teleop"])
async def teleop_switch(request: Request, body: TeleopSwitch) -> StrictJSON:
    """Switch driving on (409 during a mission, while the e-stop is latched, the robot is not
    standing or the governor refuses every motion, saying why) or off (the robot stops)."""
    worker = ctx(request).desk.worker
    if body.on:
        refused = worker.start_teleop()
        if refused:
            return StrictJSON({"detail": f"cannot drive: {refused}"}, status_code=409)
    else:
        worker.teleop.stop()
    return StrictJSON(_state(request))


@router.post("/teleop/drive", responses=_OFF, tags=["teleop"])
async def teleop_drive(request: Request, body: TeleopDrive) -> StrictJSON:
    """The pad's deflection; the answer is what the robot was last sent and why it is less
    than asked (a rule of the governor, a fence or an obstacle near), and `dropped`: why this
    request was not taken (it came after a newer one). 409 when driving is off."""
    teleop = ctx(request).desk.worker.teleop
    try:
        dropped = teleop.drive(body.forward, body.left, body.turn, seq=body.seq)
    except RuntimeError as exc:
        return StrictJSON({"detail": str(exc)}, status_code=409)
    return StrictJSON(_state(request, dropped))
