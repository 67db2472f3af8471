"""The Go2's voice over real DDS: `shadowhound node -p robot:=go2` with `shadowhound sim-driver`
(as test_go2_sim.py does), and this process listening where go2_ros2_sdk's tts_node listens.
"say hello" publishes exactly one std_msgs/String there; the robot still waves. With
`speech.speak_results` each mission's outcome is said there too. The node also serves the
dashboard: its teleop pad drives the Go2 over cmd_vel, judged by the driver's truth. Skipped
without rclpy or the interface packages unless SHADOWHOUND_REQUIRE_ROS=1 (then it fails).
"""

from __future__ import annotations

import itertools
import json
import math
import signal
import threading
import time
from collections.abc import Callable, Iterator

import pytest

from tests.ros.needs import require

require("rclpy", "shadowhound_interfaces", "go2_interfaces")

from go2_interfaces.msg import WebRtcReq  # noqa: E402
from std_msgs.msg import String  # noqa: E402

from tests.ros.rosclient import (  # noqa: E402
    Agent,
    Inbox,
    NodeProcess,
    RosClient,
    wait_matched,
    wait_until,
)
from tests.ros.test_go2_truth import free_port  # noqa: E402

NS = "/robot0"
SPEECH = "/voice_test/tts"  # a speech topic of this test's own (the default is /tts)
TIMEOUT = 30.0


PORT = free_port()
pytestmark = pytest.mark.filterwarnings("ignore:module 'sre_:DeprecationWarning")


class Driver:
    """The simulated driver's request log (what the robot was asked to do), matched both ways."""

    def __init__(self, client: RosClient) -> None:
        self.client = client
        self.requests = client.subscribe(String, f"{NS}/sim_driver/requests")
        self.webrtc = client.publisher(WebRtcReq, f"{NS}/webrtc_req")
        self.truth = client.subscribe(String, f"{NS}/sim_driver/truth")  # last reader: 50 Hz

    def wait_ready(self, process: NodeProcess) -> None:
        def ping() -> Callable[[], bool]:
            mark = self.requests.mark()
            self.webrtc.publish(WebRtcReq(id=0, topic="", api_id=0, parameter="{", priority=0))
            return lambda: 0 in self.api_ids(mark)

        wait_matched(
            self.client,
            "the simulated driver",
            [self.requests, self.truth],
            [self.webrtc],
            ping=ping,
            alive=process.check_alive,
        )

    def api_ids(self, mark: int = 0) -> list[int]:
        return [json.loads(m.data)["api_id"] for m in self.requests.since(mark)]


@pytest.fixture(scope="module")
def rig() -> Iterator[tuple[Agent, Driver]]:
    client = RosClient("shadowhound_go2_voice_test_client")
    driver_process = NodeProcess("-r", f"__ns:={NS}", command="sim-driver")
    node = NodeProcess(
        "-p",
        "robot:=go2",
        "-p",
        f"robot_namespace:={NS[1:]}",
        "-p",
        f"speech_topic:={SPEECH}",
        "-p",
        "enable_web_ui:=true",
        "-p",
        f"web_interface_port:={PORT}",
        env={"SHADOWHOUND_SPEECH__SPEAK_RESULTS": "true"},
    )
    agent, driver = Agent(client, speech_topic=SPEECH), Driver(client)
    try:
        agent.wait_ready(node)  # also proves the node's speech writer matched this reader
        driver.wait_ready(driver_process)
        wait_until(
            lambda: agent.robot_state()["connected"],
            TIMEOUT,
            "the node's Go2 robot to receive odometry",
        )
        assert f"speech on {SPEECH}" in node.output(), node.output()[-2000:]
        yield agent, driver
        node.check_alive()
        driver_process.check_alive()
    finally:
        codes = {"node": node.stop(signal.SIGINT), "driver": driver_process.stop(signal.SIGTERM)}
        client.close()
    assert codes == {"node": 0, "driver": 0}, (
        node.output()[-2000:],
        driver_process.output()[-2000:],
    )


def said(speech: Inbox, mark: int) -> list[str]:
    return [m.data for m in speech.since(mark)]


def test_say_hello_publishes_one_string_on_the_speech_topic_and_waves(rig) -> None:
    agent, driver = rig
    speech = agent.speech
    assert speech is not None
    mark, requests = speech.mark(), driver.requests.mark()
    final = agent.run("say hello", 60.0)
    assert final.startswith("COMPLETED: "), final
    assert 'said "Hello!" aloud' in final, final
    speech.wait_for(lambda m: True, 5.0, "the words on the speech topic", mark)
    assert 1016 in driver.api_ids(requests)  # the wave (Hello) still reaches the driver
    # The next saying arrives after it on the same topic from the same writer: had "say
    # hello" published twice, the second copy would be here before it.
    final = agent.run("say good morning", 60.0)
    assert final.startswith("COMPLETED: "), final
    speech.wait_for(lambda m: m.data == "Good morning!", 5.0, "the second saying", mark)
    assert said(speech, mark) == ["Hello!", "Good morning!"]


def test_an_answer_said_aloud_is_cut_and_clean_on_the_wire(rig) -> None:
    agent, _ = rig
    speech = agent.speech
    assert speech is not None
    mark = speech.mark()
    final = agent.run("tell me where you are and say it out loud", 60.0)
    assert final.startswith("COMPLETED: "), final
    speech.wait_for(lambda m: True, 5.0, "the answer on the speech topic", mark)
    [words] = said(speech, mark)
    assert 0 < len(words) <= 200 and words.isprintable(), words
    assert words.startswith("Standing at x=") and "battery" in words, words


def test_with_speak_results_a_missions_outcome_is_said_on_the_speech_topic(rig) -> None:
    agent, _ = rig
    speech = agent.speech
    assert speech is not None
    mark = speech.mark()
    final = agent.run("turn left 10 degrees", 60.0)
    assert final.startswith("COMPLETED: "), final
    message = speech.wait_for(lambda m: True, 5.0, "the outcome on the speech topic", mark)
    # The mission's own result (a turn on a busy machine may say it ended a little short).
    assert message.data.startswith("Done: ") and message.data[:60] in final, (message.data, final)
    assert len(said(speech, mark)) == 1


def test_the_dashboards_pad_drives_the_go2_over_cmd_vel(rig) -> None:
    """The pad on the node's own dashboard: the Go2 moves (the driver's truth) and stops when
    the pad is let go; the only way a velocity reaches the driver is its cmd_vel."""
    import httpx

    agent, driver = rig
    web = httpx.Client(base_url=f"http://127.0.0.1:{PORT}", timeout=10)
    assert agent.run("stand up", 60.0).startswith("COMPLETED: ")
    switched = web.post("/api/teleop", json={"on": True})
    assert switched.status_code == 200 and switched.json()["on"], switched.text

    def truth() -> dict:
        mark = driver.truth.mark()
        return json.loads(driver.truth.wait_for(lambda _m: True, 5.0, "truth", mark).data)

    start = truth()
    held = threading.Event()
    numbers = itertools.count(1)  # the page numbers its requests (a late one is dropped)
    answers: list[httpx.Response] = []

    def hold() -> None:  # the page, sending the stick back every 0.1 s
        while not held.wait(0.1):
            answers.append(
                web.post("/api/teleop/drive", json={"forward": -0.6, "seq": next(numbers)})
            )

    thread = threading.Thread(target=hold, daemon=True)
    thread.start()
    try:
        wait_until(
            lambda: math.dist((truth()["x"], truth()["y"]), (start["x"], start["y"])) > 0.15,
            TIMEOUT,
            "the Go2 to back up (truth)",
        )
    finally:
        held.set()
        thread.join()
    assert answers and all(a.status_code == 200 for a in answers), answers[-1].text
    let_go = web.post("/api/teleop/drive", json={"forward": 0.0, "seq": next(numbers)})
    assert let_go.status_code == 200, let_go.text
    wait_until(lambda: not truth()["moving"], 5.0, "the Go2 to stop (truth)")
    stopped = truth()
    time.sleep(0.5)
    assert math.dist((truth()["x"], truth()["y"]), (stopped["x"], stopped["y"])) < 0.01
    assert web.post("/api/teleop", json={"on": False}).json()["on"] is False
    web.close()
