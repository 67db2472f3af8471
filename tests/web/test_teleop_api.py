"""Driving over HTTP (issue 27): `POST /api/teleop` and `/api/teleop/drive` on a real server,
the simulated robot in real time, judged by its true state. Issue 32: the governor's rules, late
requests, nobody driving."""

from __future__ import annotations

import itertools
import math
import threading
import time
from collections.abc import Callable
from typing import Any

import httpx
import pytest

from shadowhound.robot.sim.robot import SimRobot
from shadowhound.teleop import HEARTBEAT
from shadowhound.web import WebServer
from tests.web.conftest import approach, make_agent, wait_for

SEQ = itertools.count(1)  # the pages' request numbers: growing, as a page's clock


def switch(server: WebServer, on: bool) -> httpx.Response:
    return httpx.post(server.url + "/api/teleop", json={"on": on})


def drive(
    server: WebServer,
    forward: float = 0.0,
    left: float = 0.0,
    turn: float = 0.0,
    seq: int | None = None,
) -> Any:
    body = {"seq": next(SEQ) if seq is None else seq, "forward": forward, "left": left}
    return httpx.post(server.url + "/api/teleop/drive", json={**body, "turn": turn})


class Holder:
    """A page holding the stick: the same deflection sent every 0.1 s until released."""

    def __init__(self, server: WebServer, forward: float = 0.0, turn: float = 0.0) -> None:
        self.server, self.stick = server, (forward, 0.0, turn)
        self.answers: list[dict] = []
        self._done = threading.Event()
        self._thread = threading.Thread(target=self._run, daemon=True)
        self._thread.start()

    def _run(self) -> None:
        while not self._done.wait(0.1):
            reply = drive(self.server, *self.stick)
            if reply.status_code == 200:
                self.answers.append(reply.json())

    def quit(self) -> None:
        """Stop sending, without letting go (a page that closed)."""
        self._done.set()
        self._thread.join()

    def release(self) -> None:
        self.quit()
        drive(self.server)  # let go: zero


def test_the_pad_drives_the_robot_and_letting_go_stops_it(serve: Callable[..., WebServer]) -> None:
    agent = make_agent(time_scale=1.0)
    server = serve(agent)
    assert drive(server, forward=0.5).status_code == 409  # off until switched on
    assert switch(server, True).json()["on"] is True
    holder = Holder(server, forward=-0.6)
    wait_for(lambda: agent.robot.get_state().x < -0.3, 10, "the robot to back up")
    state = agent.robot.get_state()
    assert state.vx < -0.1 and abs(state.y) < 0.05
    assert holder.answers and holder.answers[-1]["sent"]["vx"] < 0
    holder.release()
    wait_for(lambda: agent.robot.get_state().vx == 0.0, 5, "the robot to stop on release")
    # Turning in place with the stick sideways.
    holder = Holder(server, turn=0.8)
    wait_for(lambda: agent.robot.get_state().yaw > 0.3, 10, "the robot to turn left")
    holder.release()
    wait_for(lambda: agent.robot.get_state().wz == 0.0, 5, "the turn to stop")
    assert switch(server, False).json()["on"] is False


def test_a_page_that_goes_quiet_stops_the_robot(serve: Callable[..., WebServer]) -> None:
    agent = make_agent(time_scale=1.0)
    server = serve(agent)
    switch(server, True)
    holder = Holder(server, forward=-0.6)
    wait_for(lambda: agent.robot.get_state().vx < -0.1, 10, "the robot to back up")
    holder.quit()  # no release: the page closed mid-drive
    wait_for(lambda: agent.robot.get_state().vx == 0.0, 3, "the dead-man to stop the robot")
    x = agent.robot.get_state().x
    time.sleep(0.3)
    assert agent.robot.get_state().x == pytest.approx(x, abs=0.005)  # it stays stopped


def test_the_pad_cannot_take_the_body_over_the_fence_or_into_the_red_ball(
    serve: Callable[..., WebServer],
) -> None:
    agent = make_agent(time_scale=1.0, safety={"geofence_radius": 2.0})
    server = serve(agent)
    robot = agent.robot
    assert isinstance(robot, SimRobot)
    margin = agent.settings.safety.geofence_margin
    switch(server, True)
    holder = Holder(server, forward=-1.0)  # full back, toward the fence 2 m behind
    wait_for(lambda: holder.answers and "geofence" in holder.answers[-1]["limited"], 10, "limit")
    wait_for(lambda: robot.get_state().vx == 0.0, 10, "the robot to stop at the fence")
    holder.release()
    assert math.hypot(robot.get_state().x, robot.get_state().y) <= 2.0 - margin + 0.02
    # Full ahead from the start, with the default fence: the red ball (3, 0) is in the way.
    switch(server, False)
    wide = make_agent(time_scale=1.0)
    server = serve(wide)
    switch(server, True)
    holder = Holder(server, forward=1.0)
    closest = approach(wide.robot, "red ball")
    holder.release()
    assert closest > 0.0, closest  # the body never touched the ball (truth)
    assert wide.robot.get_state().x > 1.5  # it did drive up to it


def test_driving_and_missions_exclude_each_other(serve: Callable[..., WebServer]) -> None:
    agent = make_agent(time_scale=1.0)
    server = serve(agent)
    switch(server, True)
    refused = httpx.post(server.url + "/api/mission", json={"command": "sit down"})
    assert refused.status_code == 409 and "teleop" in refused.json()["detail"]
    switch(server, False)
    httpx.post(server.url + "/api/mission", json={"command": "walk backward 2 meters"})
    wait_for(lambda: agent.robot.get_state().vx < -0.1, 10, "the mission's walk")
    busy = switch(server, True)
    assert busy.status_code == 409 and "a mission is running" in busy.json()["detail"]
    httpx.post(server.url + "/api/estop")
    latched = switch(server, True)
    assert latched.status_code == 409 and "e-stop is latched" in latched.json()["detail"]


def test_the_estop_ends_driving(serve: Callable[..., WebServer]) -> None:
    agent = make_agent(time_scale=1.0)
    server = serve(agent)
    switch(server, True)
    holder = Holder(server, forward=-0.6)
    wait_for(lambda: agent.robot.get_state().vx < -0.1, 10, "the robot to back up")
    httpx.post(server.url + "/api/estop")
    holder.quit()
    assert agent.robot.get_state().vx == 0.0
    assert httpx.get(server.url + "/api/teleop").json()["on"] is False
    assert drive(server, forward=-0.6).status_code == 409


@pytest.mark.parametrize(
    "body",
    [
        {"seq": 1, "forward": 2},
        {"seq": 1, "forward": True},
        {"seq": 1, "turn": "left"},
        {"seq": 1, "forward": 0.1, "speed": 3},
        [1],
        {"forward": 0.5},
        {"seq": 0, "forward": 0.5},
        {"seq": 1.5, "forward": 0.5},
        {"seq": "7", "forward": 0.5},
        {"seq": True, "forward": 0.5},
        {"seq": 2**53, "forward": 0.5},
    ],
)
def test_bad_drive_input_is_refused_naming_it_and_moves_nothing(
    serve: Callable[..., WebServer], body: object
) -> None:
    agent = make_agent(time_scale=1.0)
    server = serve(agent)
    switch(server, True)
    reply = httpx.post(server.url + "/api/teleop/drive", json=body)
    assert reply.status_code == 422 and "invalid request" in reply.json()["detail"]
    assert agent.robot.get_state().vx == 0.0


def test_a_drive_without_its_number_says_so(serve: Callable[..., WebServer]) -> None:
    """A page older than the server (no `seq`) is told what is missing, and moves nothing."""
    agent = make_agent(time_scale=1.0)
    server = serve(agent)
    switch(server, True)
    reply = httpx.post(server.url + "/api/teleop/drive", json={"forward": -0.6})
    assert reply.status_code == 422
    assert "seq is required" in reply.json()["detail"] and "reload" in reply.json()["detail"]
    assert agent.robot.get_state().vx == 0.0


@pytest.mark.parametrize(
    ("settings", "why"),
    [
        ({}, "the battery is at 5%, below the floor of 15% (safety.battery_floor)"),
        ({"deny_skills": ["nav.*"]}, "nav.move is in safety.deny_skills"),
    ],
)
def test_the_pad_keeps_the_rules_missions_keep(
    serve: Callable[..., WebServer], settings: dict[str, Any], why: str
) -> None:
    """At 5% battery (the floor is 15%), or with every nav.* skill denied, a mission may not
    move the robot: nor may the pad (judged by truth)."""
    agent = make_agent(time_scale=1.0, safety=settings)
    robot = agent.robot
    assert isinstance(robot, SimRobot)
    if not settings:
        robot.set_battery(5.0)
    mission = agent.execute_mission("walk backward 1 meter")
    assert not mission.success and why in mission.response  # as the governor refuses it
    server = serve(agent)
    refused = switch(server, True)
    assert refused.status_code == 409, refused.text
    assert why in refused.json()["detail"]
    assert drive(server, forward=-1.0).status_code == 409
    assert robot.true_odometer == 0.0


def test_a_request_that_arrives_after_the_release_is_dropped(
    serve: Callable[..., WebServer],
) -> None:
    """A page's drive (n) overtaken by its release (n + 1) arrives last: it is dropped, and the
    robot, stopped by the release, is sent no motion again (truth: its command log)."""
    agent = make_agent(time_scale=1.0)
    robot = agent.robot
    assert isinstance(robot, SimRobot)
    server = serve(agent)
    switch(server, True)
    holder = Holder(server, forward=-0.6)
    wait_for(lambda: robot.get_state().vx < -0.1, 10, "the robot to back up")
    holder.quit()
    late, release = next(SEQ), next(SEQ)
    assert drive(server, seq=release).json()["dropped"] == ""
    released = len(robot.commands)
    answer = drive(server, forward=-0.6, seq=late).json()
    assert f"request {late} came after request {release}" in answer["dropped"]
    wait_for(lambda: robot.get_state().vx == 0.0, 5, "the robot to stop")
    time.sleep(HEARTBEAT + 0.2)  # as long as the late request would have driven it
    moved = [c for c in robot.commands[released:] if c.kind == "velocity" and any(c.value)]
    assert not moved, moved
    switch(server, False)


def test_nobody_driving_switches_driving_off_and_missions_run_again(
    serve: Callable[..., WebServer],
) -> None:
    agent = make_agent(time_scale=1.0, teleop={"idle_timeout": 0.5})
    server = serve(agent)
    on = switch(server, True).json()
    assert on["on"] is True and on["idle_timeout"] == 0.5
    busy = httpx.post(server.url + "/api/mission", json={"command": "turn left 10 degrees"})
    assert busy.status_code == 409 and "teleop.idle_timeout" in busy.json()["detail"]
    wait_for(lambda: not httpx.get(server.url + "/api/teleop").json()["on"], 10, "switch-off")
    state = httpx.get(server.url + "/api/teleop").json()
    assert "nobody drove for 0.5 s (teleop.idle_timeout)" in state["ended"]
    taken = httpx.post(server.url + "/api/mission", json={"command": "turn left 10 degrees"})
    assert taken.status_code == 202, taken.text
