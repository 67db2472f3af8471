"""The HTTP API in-process (TestClient): missions, e-stop, approvals, chat, status, camera."""

from __future__ import annotations

import base64
import subprocess
import sys

import pytest
from fastapi.testclient import TestClient

from shadowhound import RobotAgent
from shadowhound.web import create_app
from shadowhound.web.models import MAX_BODY
from tests.images import tiny_jpeg
from tests.web.conftest import finished, make_agent, wait_for


def test_health_keeps_the_original_answer(client: TestClient) -> None:
    body = client.get("/api/health").json()
    assert body["status"] == "healthy" and body["service"] == "shadowhound-web"


def test_mission_is_accepted_with_an_id_and_runs(client: TestClient, agent: RobotAgent) -> None:
    reply = client.post("/api/mission", json={"command": "walk forward 1 meter"})
    assert reply.status_code == 202
    body = reply.json()
    # The original ShadowHound answer's keys, plus the mission id.
    assert body["success"] is True and body["command"] == "walk forward 1 meter"
    assert body["message"] and body["mission_id"]
    record = finished(client, body["mission_id"])
    assert record["status"] == "succeeded", record
    assert record["result"]["mission_id"] == body["mission_id"]
    assert [s["status"] for s in record["result"]["steps"]] == ["succeeded"]
    assert abs(agent.get_robot_state().x - 1.0) < 0.05
    listed = client.get("/api/missions").json()["missions"]
    assert listed[0]["mission_id"] == body["mission_id"]
    # The web id is the agent's id: its history has the mission under the same id.
    assert agent.history[-1].mission_id == body["mission_id"]


def test_missions_from_other_interfaces_are_listed(client: TestClient, agent: RobotAgent) -> None:
    web = client.post("/api/mission", json={"command": "stand up"}).json()["mission_id"]
    finished(client, web)
    other = agent.execute_mission("sit down", mission_id="ros-topic-1")  # e.g. a ROS topic
    listed = client.get("/api/missions").json()["missions"]
    assert [(m["mission_id"], m["source"]) for m in listed] == [
        (web, "web"),
        (other.mission_id, "agent"),
    ]
    assert listed[1]["command"] == "sit down" and listed[1]["success"] is True


def test_original_body_with_priority_is_accepted(client: TestClient) -> None:
    reply = client.post("/api/mission", json={"command": "stand up", "priority": 0})
    assert reply.status_code == 202
    finished(client, reply.json()["mission_id"])


def test_failed_mission_says_why(client: TestClient) -> None:
    reply = client.post("/api/mission", json={"command": "juggle three flaming torches"})
    record = finished(client, reply.json()["mission_id"])
    assert record["success"] is False and record["status"] == "failed"
    assert record["response"]


def test_dry_run_plans_without_moving(client: TestClient, agent: RobotAgent) -> None:
    reply = client.post("/api/mission", json={"command": "walk forward 2 meters", "dry_run": True})
    assert reply.status_code == 202
    record = finished(client, reply.json()["mission_id"])
    assert record["dry_run"] is True and record["success"] is True
    path = record["result"]["predicted_path"]
    assert abs(path[-1]["x"] - 2.0) < 0.01
    assert agent.get_robot_state().x == 0.0


def test_bad_requests_get_clear_4xx(client: TestClient) -> None:
    cases = [
        ({"command": ""}, "at least 1 character"),
        ({"command": 5}, "valid string"),
        ({}, "command"),
        ({"command": "stand", "speed": 3}, "speed"),
        ({"command": "x" * 3000}, "limit is 2000"),
        ({"command": "   "}, "empty"),
    ]
    for body, words in cases:
        reply = client.post("/api/mission", json=body)
        assert reply.status_code == 422, (body, reply.text)
        assert words in reply.json()["detail"], reply.json()
    reply = client.post(
        "/api/mission", content=b"{not json", headers={"content-type": "application/json"}
    )
    assert reply.status_code == 422
    big = client.post(
        "/api/mission", content=b"x" * (MAX_BODY + 1), headers={"content-type": "application/json"}
    )
    assert big.status_code == 413 and "larger than" in big.json()["detail"]
    assert client.get("/api/missions/nope").status_code == 404
    assert client.get("/api/missions?limit=0").status_code == 422


def test_estop_latches_drops_the_queue_and_refuses_missions(client: TestClient) -> None:
    reply = client.post("/api/estop")
    assert reply.status_code == 200
    assert reply.json()["estop"] is True and reply.json()["robot"]["estopped"] is True
    refused = client.post("/api/mission", json={"command": "walk forward 1 meter"})
    assert refused.status_code == 409
    assert "e-stop" in refused.json()["detail"] and refused.json()["success"] is False
    # A dry run moves nothing, so it is still allowed.
    assert client.post("/api/mission", json={"command": "sit", "dry_run": True}).status_code == 202
    assert client.get("/api/status").json()["estop"] is True
    released = client.post("/api/estop/release")
    assert released.json()["estop"] is False
    ok = client.post("/api/mission", json={"command": "walk forward 1 meter"})
    assert finished(client, ok.json()["mission_id"])["status"] == "succeeded"


def test_cancel_a_running_mission_and_refuse_cancelling_a_finished_one() -> None:
    agent = make_agent(time_scale=1.0)  # real time: the walk takes 40 s, the cancel lands in it
    with TestClient(create_app(agent), base_url="http://127.0.0.1") as client:
        walk = {"command": "walk backward 4 meters at 0.1 m/s"}
        first = client.post("/api/mission", json=walk).json()
        queued = client.post("/api/mission", json={"command": "turn left 90 degrees"}).json()
        assert queued["queued_ahead"] >= 1
        wait_for(
            lambda: client.get("/api/status").json()["running"] == first["mission_id"],
            what="the first mission to run",
        )
        cancel_queued = client.post(f"/api/missions/{queued['mission_id']}/cancel")
        assert cancel_queued.json()["cancelled"] is True
        client.post(f"/api/missions/{first['mission_id']}/cancel")
        record = finished(client, first["mission_id"])
        assert record["status"] == "stopped", record
        dropped = finished(client, queued["mission_id"])
        assert dropped["state"] == "dropped" and "cancelled" in dropped["response"]
        again = client.post(f"/api/missions/{first['mission_id']}/cancel")
        assert again.status_code == 409
        assert client.post("/api/missions/nope/cancel").status_code == 404
    agent.cleanup()


def test_queue_full_is_refused_with_429() -> None:
    agent = make_agent(time_scale=1.0)
    with TestClient(create_app(agent), base_url="http://127.0.0.1") as client:
        codes = [
            client.post("/api/mission", json={"command": "wait 30 seconds"}).status_code
            for _ in range(12)
        ]
        assert codes[0] == 202 and 429 in codes
        client.post("/api/estop")  # ends the waiting mission and drops the queue
    agent.cleanup()


def test_risky_trick_waits_for_approval_and_can_be_approved_or_rejected() -> None:
    agent = make_agent()
    with TestClient(create_app(agent), base_url="http://127.0.0.1") as client:
        assert agent.approvals_enabled
        for decision in ("reject", "approve"):
            mission = client.post("/api/mission", json={"command": "do a backflip"}).json()
            pending = wait_for(
                lambda: client.get("/api/approval").json()["pending"], what="an approval request"
            )
            assert pending["reasons"]
            assert client.post("/api/approval/wrong-id/approve").status_code == 404
            reply = client.post(f"/api/approval/{pending['request_id']}/{decision}")
            assert reply.status_code == 200
            record = finished(client, mission["mission_id"])
            assert record["success"] is (decision == "approve"), record
        assert client.get("/api/approval").json()["pending"] is None
    agent.cleanup()


def test_chat_status_diagnostics_skills_map(client: TestClient) -> None:
    answer = client.post("/api/chat", json={"text": "where are you?"}).json()
    assert "x=" in answer["answer"]
    assert client.post("/api/chat", json={"text": ""}).status_code == 422
    status = client.get("/api/status").json()
    assert status["status"] == "idle" and status["robot"]["x"] == 0.0
    diagnostics = client.get("/api/diagnostics").json()
    assert diagnostics["agent_backend"] == "offline" and "limits" in diagnostics
    assert diagnostics["web"]["auth"] is False
    # Which robot this is, in words the page's header shows.
    assert diagnostics["robot_description"] == "simulated Go2"
    assert diagnostics["robot_name"] == "sim-go2"
    skills = {s["name"] for s in client.get("/api/skills").json()["skills"]}
    assert {"nav.move", "nav.rotate", "body.stand"} <= skills
    world = client.get("/api/map").json()
    assert "kitchen" in world["places"] and world["geofence_radius"] > 0


def test_map_shows_taught_places_with_the_profiles(client: TestClient, agent: RobotAgent) -> None:
    kitchen = agent.settings.places["kitchen"]
    taught = agent.execute_mission("walk forward 1 meter, remember this spot as the porch")
    assert taught.success, taught.response
    places = client.get("/api/map").json()["places"]
    assert places["kitchen"] == list(kitchen)  # the profile's
    assert places["porch"] == pytest.approx([1.0, 0.0], abs=0.05)  # taught where it stood


def test_camera_latest_is_jpeg_and_the_original_json_form_still_works(
    client: TestClient, agent: RobotAgent
) -> None:
    reply = client.get("/api/camera/latest")  # the simulator renders PNG; served as JPEG
    assert reply.status_code == 200 and reply.headers["content-type"] == "image/jpeg"
    assert reply.content[:2] == b"\xff\xd8"
    frame = tiny_jpeg(32, 24)
    agent.update_camera_image(frame)
    assert client.get("/api/camera/latest").content == frame  # passed through unchanged
    legacy = client.get("/api/camera/latest?format=json").json()
    assert legacy["available"] is True and base64.b64decode(legacy["image"]) == frame
    assert (
        client.get("/api/camera/latest", headers={"accept": "application/json"}).json()["available"]
        is True
    )


def test_page_and_static_files_are_served(client: TestClient) -> None:
    page = client.get("/")
    assert page.status_code == 200 and 'id="estop"' in page.text
    assert "default-src 'self'" in page.headers["content-security-policy"]
    for name in ("app.js", "style.css"):
        assert client.get(f"/static/{name}").status_code == 200


def test_importing_shadowhound_does_not_import_the_web_stack() -> None:
    code = (
        "import sys, shadowhound, shadowhound.web; "
        "bad = [m for m in ('fastapi', 'uvicorn', 'starlette') if m in sys.modules]; "
        "assert not bad, bad"
    )
    subprocess.run([sys.executable, "-c", code], check=True, timeout=60)


# -- strict types at the HTTP edge ----------------------------------------------------------------


def _field_is_valid(field: str, value: object) -> bool:
    """The reference reading of MissionRequest's optional fields: JSON types are not converted
    (a string is not a boolean, a boolean is not a number)."""
    if field == "dry_run":
        return type(value) is bool
    if field == "priority":
        return value is None or type(value) is int and 0 <= value <= 10
    raise AssertionError(field)


def test_strings_are_not_booleans_and_booleans_are_not_numbers(
    client: TestClient, agent: RobotAgent
) -> None:
    for body, where in [
        ({"command": "walk forward 1 meter", "dry_run": "yes"}, "body.dry_run"),
        ({"command": "walk forward 1 meter", "dry_run": "true"}, "body.dry_run"),
        ({"command": "walk forward 1 meter", "dry_run": 1}, "body.dry_run"),
        ({"command": "walk forward 1 meter", "priority": True}, "body.priority"),
        ({"command": "walk forward 1 meter", "priority": "1"}, "body.priority"),
        ({"command": "walk forward 1 meter", "priority": 1.5}, "body.priority"),
        ({"command": True}, "body.command"),
    ]:
        reply = client.post("/api/mission", json=body)
        assert reply.status_code == 422, (body, reply.text)
        problems = reply.json()["problems"]
        assert [p["where"] for p in problems] == [where], (body, problems)
        assert where in reply.json()["detail"]
    assert client.post("/api/chat", json={"text": False}).status_code == 422
    reply = client.post("/api/approval/x/reject", json={"reason": 0})
    assert reply.status_code == 422 and reply.json()["problems"][0]["where"] == "body.reason"
    assert client.get("/api/missions").json()["missions"] == []  # nothing was queued
    assert agent.get_robot_state().x == 0.0


def test_mission_fields_accept_exactly_their_json_type(client: TestClient) -> None:
    """Property: for any JSON value in `dry_run` or `priority`, the request is refused (422,
    naming the field) exactly when the value is not of the field's JSON type and range."""
    from hypothesis import HealthCheck, given, settings
    from hypothesis import strategies as st

    scalars = st.one_of(
        st.none(),
        st.booleans(),
        st.integers(-20, 20),
        st.floats(allow_nan=False, allow_infinity=False),
        st.text(max_size=6),
        st.sampled_from(["yes", "no", "true", "false", "1", "0", "on", "off"]),
    )
    values = st.one_of(
        scalars,
        st.lists(scalars, max_size=2),
        st.dictionaries(st.text(max_size=3), scalars, max_size=2),
    )

    @settings(
        max_examples=150,
        deadline=None,
        database=None,
        suppress_health_check=[HealthCheck.function_scoped_fixture],
    )
    @given(st.sampled_from(["dry_run", "priority"]), values)
    def check(field: str, value: object) -> None:
        # A dry run never moves the robot, so accepted requests cost nothing.
        body = {"command": "walk forward 1 meter", "dry_run": True, field: value}
        reply = client.post("/api/mission", json=body)
        valid = _field_is_valid(field, value)
        assert (reply.status_code != 422) == valid, (body, reply.text)
        if not valid:
            assert [p["where"] for p in reply.json()["problems"]] == [f"body.{field}"]

    check()


def test_every_mission_within_the_text_limit_fits_in_a_body(agent: RobotAgent) -> None:
    """413 is about bytes, the mission limit about characters: a command of the longest allowed
    length in the most expensive JSON spelling still reaches the route (and is judged there)."""
    from shadowhound.web.models import MAX_TEXT

    wide = make_agent(agent={"max_mission_chars": MAX_TEXT})
    with TestClient(create_app(wide), base_url="http://127.0.0.1") as client:
        text = "\U0001f600" * (MAX_TEXT - 20) + " stand up"  # each escaped as 12 bytes
        body = (
            '{"command": "'
            + text.encode("unicode_escape").decode().replace("\\U0001f600", "\\ud83d\\ude00")
            + '", "dry_run": true}'
        )
        assert len(body.encode()) > 12 * (MAX_TEXT - 20)
        reply = client.post(
            "/api/mission", content=body.encode(), headers={"content-type": "application/json"}
        )
        assert reply.status_code == 202, reply.text[:300]
        over = client.post("/api/mission", json={"command": "x" * (MAX_TEXT + 1)})
        assert over.status_code == 422 and over.json()["problems"][0]["where"] == "body.command"
    wide.cleanup()


def test_patrol_until_i_say_stop_ends_as_asked_on_the_dashboards_cancel() -> None:
    """Issue 26: the dashboard's stop is the person's "stop": the mission succeeds, as asked."""
    agent = make_agent(time_scale=1.0)
    with TestClient(create_app(agent), base_url="http://127.0.0.1") as client:
        body = client.post("/api/mission", json={"command": "patrol until I say stop"}).json()
        wait_for(
            lambda: agent.robot.get_state().distance_travelled > 0.2,
            what="the patrol to walk (the simulator's odometer)",
        )
        assert client.post(f"/api/missions/{body['mission_id']}/cancel").json()["cancelled"]
        record = finished(client, body["mission_id"])
        assert record["status"] == "succeeded", record
        assert "stopped: you said stop (until I say stop)" in record["result"]["response"]
    agent.cleanup()
