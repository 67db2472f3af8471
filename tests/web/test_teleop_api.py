"""Driving over HTTP (issue 27): `POST /api/teleop` and `/api/teleop/drive` on a real server,
the simulated robot in real time, judged by its true state."""

from __future__ import annotations

import math
import threading
import time
from collections.abc import Callable
from typing import Any

import httpx
import pytest

from shadowhound.robot.sim.robot import SimRobot
from shadowhound.web import WebServer
from tests.web.conftest import approach, make_agent, wait_for


def switch(server: WebServer, on: bool) -> httpx.Response:
    return httpx.post(server.url + "/api/teleop", json={"on": on})


def drive(server: WebServer, forward: float = 0.0, left: float = 0.0, turn: float = 0.0) -> Any:
    return httpx.post(
        server.url + "/api/teleop/drive", json={"forward": forward, "left": left, "turn": turn}
    )


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
    [{"forward": 2}, {"forward": True}, {"turn": "left"}, {"forward": 0.1, "speed": 3}, [1]],
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
