"""A spoken stop (issue 27: the robot's velocity zero within 100 ms of the transcript).

Run:  .venv/bin/python bench/bench_speech.py [--write]
--write replaces the "speech" section of bench/RESULTS.md with the figures measured now.

The dashboard on a real server (loopback), a scripted OpenAI-compatible transcription server,
the simulated robot in real time walking backward 3 m. A WAV is posted to `POST /api/speech`
and transcribed as "stop"; measured: from the moment the transcription server sends its
answer to the moment the simulator's true velocity is zero (a watcher thread reads it every
0.5 ms), and the whole request as the client sees it (upload, transcription, e-stop, answer).
"""

from __future__ import annotations

import argparse
import platform
import statistics
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from results import write_section  # noqa: E402

TRIALS = 7


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    args = parser.parse_args()
    import httpx

    from shadowhound import RobotAgent, RobotAgentConfig, SimRobot
    from shadowhound.config import ShadowHoundConfig
    from shadowhound.web import WebServer, create_app
    from tests.speech_server import ScriptedTranscriber
    from tests.web.test_speech_api import wav

    recording = wav(0.5)
    to_zero, request = [], []
    with ScriptedTranscriber() as heard:
        settings = ShadowHoundConfig(speech={"base_url": heard.url})
        settings.memory.enabled = False
        robot = SimRobot(settings.sim, time_scale=1.0)
        agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
        agent.initialize()
        server = WebServer(create_app(agent), "127.0.0.1", 0).start()
        try:
            for _ in range(TRIALS):
                agent.release_estop()
                httpx.post(server.url + "/api/mission", json={"command": "walk backward 3 meters"})
                while robot.get_state().vx > -0.1:
                    time.sleep(0.005)
                stopped: list[float] = []

                def watch(stopped: list[float] = stopped) -> None:
                    while robot.get_state().vx != 0.0:
                        time.sleep(0.0005)
                    stopped.append(time.monotonic())

                watcher = threading.Thread(target=watch)
                watcher.start()
                heard.script("Stop!")
                t = time.perf_counter()
                reply = httpx.post(
                    server.url + "/api/speech",
                    content=recording,
                    headers={"content-type": "audio/wav"},
                    timeout=30,
                )
                request.append((time.perf_counter() - t) * 1000)
                watcher.join(10)
                assert reply.json().get("estop") is True, reply.text
                to_zero.append((stopped[0] - heard.requests[-1].at) * 1000)
                while robot.get_state().x < -0.05:  # walk back for the next trial
                    agent.release_estop()
                    agent.execute_mission("go to x=0, y=0")
        finally:
            server.stop()
            agent.cleanup()
    lines = [
        "<!-- speech:start -->",
        "## A spoken stop (issue 27)",
        "",
        f"Measured {time.strftime('%Y-%m-%d')} with `python bench/bench_speech.py --write` "
        f"(CPython {platform.python_version()}, {platform.machine()}), {TRIALS} trials: the "
        'dashboard on a real server, a scripted transcription server answering "Stop!", the '
        "simulated robot walking backward in real time.",
        "",
        "| what | target | median | max |",
        "|---|---|---|---|",
        f"| the transcript's answer sent to the robot's true velocity zero | < 100 ms | "
        f"{statistics.median(to_zero):.1f} ms | {max(to_zero):.1f} ms |",
        f"| the whole `POST /api/speech` as the client sees it (a 0.5 s WAV) | - | "
        f"{statistics.median(request):.1f} ms | {max(request):.1f} ms |",
        "",
        "A spoken stop is the e-stop: the simulator's e-stop is a hard stop (velocity to zero "
        "at once), so this is the software path from transcript to robot; a real Go2 then "
        "brakes in its own time, as the teleop section's standstill shows.",
        "<!-- speech:end -->",
    ]
    section = "\n".join(lines)
    print(section)
    if args.write:
        write_section("speech", section)


if __name__ == "__main__":
    main()
