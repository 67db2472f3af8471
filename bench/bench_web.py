"""Web benchmarks (issue 6): e-stop over HTTP, /api/status latency, MJPEG streaming CPU.

Run:  .venv/bin/python bench/bench_web.py [--write] [--quick]
--write replaces the "web" section of bench/RESULTS.md with the figures measured now.

The dashboard server runs in its own process (`--serve`, started by this script) on 127.0.0.1
with the simulated robot on a real clock, so its CPU time can be read from /proc and the
client's work does not share its interpreter.

- E-stop: a mission walks; after a random moment the client sends `POST /api/estop`. The
  handler calls the robot's hard stop before it answers, and the answer carries the robot state
  read after the stop, so request-sent to answer-received is an upper bound of request-to-stop.
  Every answer is checked to report the robot stopped and latched.
- Status: `GET /api/status` on one keep-alive connection at a fixed 100 requests/s for 10 s,
  while a mission runs and one dashboard WebSocket receives the live events.
- MJPEG: a thread in the server process feeds 640x480 JPEG frames at 30 frames/s through
  `agent.update_camera_image`; three clients read `/api/camera/stream?fps=30`. Server CPU is
  measured over 10 s with and without the clients (the difference is the streaming cost).
"""

from __future__ import annotations

import argparse
import io
import json
import os
import random
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path
from typing import Any

import httpx

from results import write_section

RESULTS = Path(__file__).with_name("RESULTS.md")
MISSIONS = ("walk forward 3 meters", "walk backward 3 meters")  # stays inside the geofence


def p99(values: list[float]) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(0.99 * (len(ordered) - 1)))]


# -- the server process ---------------------------------------------------------------------

def run_server(time_scale: float, camera_fps: float) -> None:
    """`--serve`: the dashboard on a free port; prints the port, runs until stdin closes."""
    from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
    from shadowhound.web import WebServer, create_app

    settings = ShadowHoundConfig()
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(settings.sim, time_scale=time_scale),
                                        settings=settings))
    server = WebServer(create_app(agent), "127.0.0.1", 0).start()
    if camera_fps > 0:
        threading.Thread(target=_feed_camera, args=(agent, camera_fps), daemon=True).start()
    print(server.port, flush=True)
    sys.stdin.read()  # the parent closes stdin to stop us
    server.stop()
    agent.cleanup()


def _feed_camera(agent: Any, fps: float) -> None:
    from PIL import Image

    frames = []
    gradient = Image.linear_gradient("L").resize((640, 480))
    for _ in range(4):  # distinct frames with sensor-like noise: about 37 kB each, like a camera
        image = Image.blend(gradient, Image.effect_noise((640, 480), 16), 0.3).convert("RGB")
        out = io.BytesIO()
        image.save(out, "JPEG", quality=80)
        frames.append(out.getvalue())
    period, index, next_at = 1.0 / fps, 0, time.monotonic()
    while True:
        agent.update_camera_image(frames[index % len(frames)])
        index += 1
        next_at += period
        time.sleep(max(0.0, next_at - time.monotonic()))


class ServerProcess:
    def __init__(self, time_scale: float, camera_fps: float = 0.0) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, __file__, "--serve", "--time-scale", str(time_scale),
             "--camera-fps", str(camera_fps)], stdin=subprocess.PIPE, stdout=subprocess.PIPE,
            text=True)
        assert self.proc.stdout is not None
        self.url = f"http://127.0.0.1:{int(self.proc.stdout.readline())}"

    def cpu_seconds(self) -> float:
        fields = Path(f"/proc/{self.proc.pid}/stat").read_text().rsplit(")", 1)[1].split()
        return (int(fields[11]) + int(fields[12])) / os.sysconf("SC_CLK_TCK")

    def close(self) -> None:
        assert self.proc.stdin is not None
        self.proc.stdin.close()
        try:
            self.proc.wait(10)
        except subprocess.TimeoutExpired:
            self.proc.kill()


def _wait(check: Any, timeout: float = 15.0) -> Any:
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        value = check()
        if value:
            return value
        time.sleep(0.005)
    raise RuntimeError("timed out")


# -- measurements ---------------------------------------------------------------------------

def bench_estop(runs: int) -> list[float]:
    server = ServerProcess(time_scale=1.0)
    latencies = []
    try:
        with httpx.Client(base_url=server.url, timeout=10) as client:
            for run in range(runs):
                reply = client.post("/api/mission", json={"command": MISSIONS[run % 2]})
                mission_id = reply.json()["mission_id"]
                _wait(lambda: client.get("/api/status").json()["robot"]["moving"])
                time.sleep(random.uniform(0.0, 0.3))
                t0 = time.perf_counter()
                answer = client.post("/api/estop").json()
                latencies.append((time.perf_counter() - t0) * 1e3)
                robot = answer["robot"]
                assert robot["estopped"] and not robot["moving"], robot
                _wait(lambda mid=mission_id: client.get(f"/api/missions/{mid}").json()["state"]
                      == "finished")
                client.post("/api/estop/release")
    finally:
        server.close()
    return latencies


def bench_status(seconds: float, rate: float) -> dict[str, Any]:
    from websockets.sync.client import connect

    server = ServerProcess(time_scale=1.0)
    latencies: list[float] = []
    late = 0
    stop = threading.Event()
    received = [0]

    def listen() -> None:
        with connect(server.url.replace("http://", "ws://") + "/ws/status") as ws:
            while not stop.is_set():
                try:
                    ws.recv(timeout=0.5)
                    received[0] += 1
                except TimeoutError:
                    continue

    listener = threading.Thread(target=listen, daemon=True)
    listener.start()
    try:
        with httpx.Client(base_url=server.url, timeout=10) as client:
            client.post("/api/mission", json={"command": "walk forward 5 meters"})
            _wait(lambda: client.get("/api/status").json()["status"] == "executing")
            period, count = 1.0 / rate, int(seconds * rate)
            start = time.perf_counter()
            for i in range(count):
                due = start + i * period
                pause = due - time.perf_counter()
                if pause > 0:
                    time.sleep(pause)
                else:
                    late += 1
                t0 = time.perf_counter()
                client.get("/api/status").raise_for_status()
                latencies.append((time.perf_counter() - t0) * 1e3)
            still_running = client.get("/api/status").json()["status"] == "executing"
            client.post("/api/estop")
    finally:
        stop.set()
        listener.join(5)
        server.close()
    return {"latencies": latencies, "late": late, "ws_messages": received[0],
            "mission_running": still_running}


def bench_mjpeg(seconds: float, clients: int = 3) -> dict[str, float]:
    server = ServerProcess(time_scale=1.0, camera_fps=30.0)
    try:
        time.sleep(1.0)  # let the feeder and the interpreter settle
        base0 = server.cpu_seconds()
        time.sleep(seconds)
        idle = (server.cpu_seconds() - base0) / seconds
        counts = [0] * clients
        stop = threading.Event()

        def read(slot: int) -> None:
            with httpx.Client(timeout=10) as client, \
                    client.stream("GET", server.url + "/api/camera/stream?fps=30") as stream:
                for chunk in stream.iter_bytes():
                    counts[slot] += chunk.count(b"--shadowhound-frame")
                    if stop.is_set():
                        return

        readers = [threading.Thread(target=read, args=(i,), daemon=True) for i in range(clients)]
        for reader in readers:
            reader.start()
        time.sleep(1.0)
        c0, n0, t0 = server.cpu_seconds(), sum(counts), time.monotonic()
        time.sleep(seconds)
        busy = (server.cpu_seconds() - c0) / (time.monotonic() - t0)
        fps = (sum(counts) - n0) / (time.monotonic() - t0) / clients
        stop.set()
    finally:
        server.close()
    return {"idle": idle * 100, "streaming": busy * 100, "extra": (busy - idle) * 100,
            "fps": fps}


# -- report ---------------------------------------------------------------------------------

def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    parser.add_argument("--quick", action="store_true", help="fewer runs (a smoke test)")
    parser.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--time-scale", type=float, default=1.0, help=argparse.SUPPRESS)
    parser.add_argument("--camera-fps", type=float, default=0.0, help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.serve:
        run_server(args.time_scale, args.camera_fps)
        return
    seconds = 3.0 if args.quick else 10.0
    estop = bench_estop(10 if args.quick else 60)
    status = bench_status(seconds, 100.0)
    mjpeg = bench_mjpeg(seconds)
    lat = status["latencies"]
    rows = [
        ("e-stop request to robot stopped (HTTP round trip), p99",
         f"{p99(estop):.2f} ms", "< 20 ms",
         f"median {statistics.median(estop):.2f} ms, max {max(estop):.2f} ms, "
         f"{len(estop)} runs"),
        ("GET /api/status at 100 requests/s, p99", f"{p99(lat):.2f} ms", "< 10 ms",
         f"median {statistics.median(lat):.2f} ms, max {max(lat):.2f} ms, {len(lat)} requests, "
         f"{status['late']} sent late; mission running: {status['mission_running']}, "
         f"{status['ws_messages']} WebSocket messages meanwhile"),
        ("MJPEG 30 frames/s to 3 clients: server CPU", f"{mjpeg['streaming']:.1f} % of a core",
         "< 15 %", f"{mjpeg['extra']:.1f} % above the {mjpeg['idle']:.1f} % of the camera "
         f"feeder alone; {mjpeg['fps']:.1f} frames/s delivered per client"),
    ]
    print(json.dumps({"estop_ms": estop, "status_p99_ms": p99(lat), "mjpeg": mjpeg}, indent=1)
          if os.environ.get("BENCH_JSON") else "")
    for name, value, target, note in rows:
        print(f"{name}: {value} (target {target}; {note})")
    if args.write:
        write(rows)


def write(rows: list[tuple[str, str, str, str]]) -> None:
    lines = [
        "<!-- web:start -->",
        "## Web dashboard (`bench/bench_web.py`)",
        "",
        f"Measured {time.strftime('%Y-%m-%d')} on this machine (2 cores, shared with other "
        "work), Python " + sys.version.split()[0] + ". The server runs in its own process on "
        "127.0.0.1 with the simulated robot on a real clock; clients are httpx and websockets.",
        "",
        "| measure | result | target | notes |",
        "|---|---|---|---|",
        *[f"| {n} | {v} | {t} | {note} |" for n, v, t, note in rows],
        "",
        "Methods. E-stop: a mission walks; after a random 0-0.3 s the client posts "
        "`/api/estop`. The handler calls the robot's hard stop in the event loop before it "
        "answers, and the answer carries the state read after the stop (checked: stopped and "
        "latched), so the round trip is an upper bound of request-to-stop; it includes the "
        "HTTP parsing on both sides; a real Go2 adds its driver's command latency. "
        "Status: one keep-alive connection on a fixed 10 ms "
        "schedule while a mission runs and a WebSocket client receives the events and 5 Hz "
        "state ticks. MJPEG: a thread in the server process feeds 640x480 JPEG frames (about "
        "37 kB, noisy like a camera's) at 30 frames/s through `update_camera_image`; three "
        "clients read `/api/camera/stream?fps=30`; CPU is utime+stime of the server process "
        "from /proc over 10 s. JPEG frames pass through without decoding or re-encoding, "
        "shared by all clients; the simulator's PNG frames are converted once per frame with "
        "Pillow.",
        "<!-- web:end -->",
    ]
    write_section("web", "\n".join(lines))


if __name__ == "__main__":
    main()
