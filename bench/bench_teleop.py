"""The teleop pad's stops (issue 27: releasing stops within 100 ms, a lost page within 0.5 s;
issue 32: say exactly what those figures are: the time to the stop command, and the braking
after it).

Run:  .venv/bin/python bench/bench_teleop.py [--write]
--write replaces the "teleop" section of bench/RESULTS.md with the figures measured now.

The dashboard on a real server (loopback), the simulated robot in real time, a client that
holds the stick at full deflection (a numbered drive request every 0.1 s, as the page sends)
until the robot's true speed is the cap, 0.5 m/s. A watcher thread reads the simulator every
0.5 ms and notes when the robot has the stop command (its command log) and when its true
velocity is zero (braking at the simulated Go2's 1 m/s^2):
(i) release: from sending the zero deflection (what letting go sends);
(ii) a lost page: from sending its last drive request, nothing said after it: the server's
     dead-man (0.35 s without a request, noticed at the next control tick) ends the drive.
Each is split in two: to the stop command, and from the stop command to standstill.
"""

from __future__ import annotations

import argparse
import itertools
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


def _fig(values: list[float]) -> str:
    return f"{statistics.median(values):.0f} ms, {max(values):.0f} ms"


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    args = parser.parse_args()
    import httpx

    from shadowhound import RobotAgent, RobotAgentConfig, SimRobot
    from shadowhound.config import ShadowHoundConfig
    from shadowhound.web import WebServer, create_app

    settings = ShadowHoundConfig()
    settings.memory.enabled = False
    cap = settings.safety.max_linear_speed
    robot = SimRobot(settings.sim, time_scale=1.0)
    agent = RobotAgent(RobotAgentConfig(robot=robot, settings=settings))
    agent.initialize()
    server = WebServer(create_app(agent), "127.0.0.1", 0).start()
    seq = itertools.count(1)
    # (to the stop command, stop command to standstill, to standstill), milliseconds
    release: list[tuple[float, float, float]] = []
    lost: list[tuple[float, float, float]] = []
    client = httpx.Client(base_url=server.url)

    def drive(forward: float) -> None:
        client.post("/api/teleop/drive", json={"seq": next(seq), "forward": forward})

    try:
        client.post("/api/teleop", json={"on": True})
        for trial in range(2 * TRIALS):
            forward = -1.0 if trial % 2 else 1.0
            while abs(robot.get_state().vx) < cap - 1e-3:  # hold until at full speed
                drive(forward)
                time.sleep(0.1)
            stopped: list[float] = []

            def watch(stopped: list[float] = stopped) -> None:
                told = None
                while robot.get_state().vx != 0.0:
                    if told is None and robot.commands[-1].kind == "stop":
                        told = time.monotonic()
                    time.sleep(0.0005)
                stopped.extend([told or time.monotonic(), time.monotonic()])

            watcher = threading.Thread(target=watch)
            watcher.start()
            t = time.monotonic()  # the last word from the "page", as it sends it
            drive(0.0 if trial < TRIALS else forward)
            watcher.join(5)
            told, still = (stopped[0] - t) * 1000, (stopped[1] - t) * 1000
            (release if trial < TRIALS else lost).append((told, still - told, still))
            time.sleep(0.3)
    finally:
        client.close()
        server.stop()
        agent.cleanup()
    col = list(zip(*release, strict=True)), list(zip(*lost, strict=True))
    lines = [
        "<!-- teleop:start -->",
        "## The teleop pad's stops (issues 27, 32)",
        "",
        f"Measured {time.strftime('%Y-%m-%d')} with `python bench/bench_teleop.py --write` "
        f"(CPython {platform.python_version()}, {platform.machine()}), {TRIALS} trials each: "
        f"the dashboard on a real server, the simulated robot in real time driven at full "
        f"deflection, {cap:g} m/s (the speed cap). Median, max.",
        "",
        "| what | target (issue 27) | to the stop command at the robot | then braking to "
        "standstill (truth) | to standstill |",
        "|---|---|---|---|---|",
        f"| letting go: from sending the zero deflection | < 100 ms | {_fig(list(col[0][0]))} | "
        f"{_fig(list(col[0][1]))} | {_fig(list(col[0][2]))} |",
        "| a lost page: from sending its last drive request (dead-man: 0.35 s, then the next "
        f"control tick) | < 500 ms | {_fig(list(col[1][0]))} | {_fig(list(col[1][1]))} | "
        f"{_fig(list(col[1][2]))} |",
        "",
        "The targets are met by the stop command: the server sends it within 0.4 s of the "
        "page's last word (docs/web.md and the page say so). Standstill adds the body's "
        f"braking from {cap:g} m/s, the simulated Go2 (as the real one) decelerating within its "
        "acceleration limit (1 m/s^2): about 0.5 s from full speed, less from slower.",
        "<!-- teleop:end -->",
    ]
    section = "\n".join(lines)
    print(section)
    if args.write:
        write_section("teleop", section)


if __name__ == "__main__":
    main()
