"""Web benchmarks (issues 6, 18): e-stop idle and under load, /api/status latency, MJPEG CPU.

Run:  .venv/bin/python bench/bench_web.py [--write] [--quick] [--cases ws,sse] [--repeat 2]
--write replaces the "web" section of bench/RESULTS.md with the figures measured now;
--cases picks e-stop cases (idle, sse, ws, mjpeg; default all) and --repeat runs each of them
that many times on fresh servers (one row per case: all stops pooled, each run's p99 listed).
The 1-minute load average before and after each run goes beside its figures: on a shared
machine the OS scheduler, not the server, decides most of a slow stop.

The dashboard server runs in its own process (`--serve`, started by this script) on 127.0.0.1
with the simulated robot on a real clock, so its CPU time can be read from /proc and the
client's work does not share its interpreter.

- E-stop: a mission walks; after a random moment the client sends `POST /api/estop` (a
  minimal HTTP/1.1 client on even stops, httpx on odd ones; both figures are reported). The
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
import socket
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
MISSIONS = ("walk forward 1 meter", "walk backward 1 meter")  # clear of the red ball (2.4 m)


def p99(values: list[float]) -> float:
    ordered = sorted(values)
    return ordered[min(len(ordered) - 1, round(0.99 * (len(ordered) - 1)))]


# -- the server process ---------------------------------------------------------------------


def run_server(time_scale: float, camera_fps: float) -> None:
    """`--serve`: the dashboard on a free port; prints the port, runs until stdin closes."""
    from shadowhound import RobotAgent, RobotAgentConfig, ShadowHoundConfig, SimRobot
    from shadowhound.serving import settle_heap
    from shadowhound.web import WebServer, create_app

    class TimedRobot(SimRobot):
        """Tells the parent when each hard stop has set the velocity to zero."""

        def emergency_stop(self) -> None:
            super().emergency_stop()
            print(f"stopped {time.monotonic():.6f}", flush=True)

    settings = ShadowHoundConfig()
    agent = RobotAgent(
        RobotAgentConfig(robot=TimedRobot(settings.sim, time_scale=time_scale), settings=settings)
    )
    server = WebServer(create_app(agent), "127.0.0.1", 0).start()
    settle_heap()  # as `shadowhound serve` does once it has started
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
            [
                sys.executable,
                __file__,
                "--serve",
                "--time-scale",
                str(time_scale),
                "--camera-fps",
                str(camera_fps),
            ],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.proc.stdout is not None
        self.url = f"http://127.0.0.1:{int(self.proc.stdout.readline())}"

    def stopped_at(self) -> float:
        """When the robot's hard stop ended (time.monotonic(): on Linux CLOCK_MONOTONIC, one
        clock for every process), for the next stop not yet read."""
        assert self.proc.stdout is not None
        while not (line := self.proc.stdout.readline()).startswith("stopped "):
            if not line:
                raise RuntimeError("the server ended without reporting the stop")
        return float(line.split()[1])

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


class Load:
    """Clients in a thread of their own (one asyncio loop): `kind` is sse, ws or mjpeg."""

    def __init__(self, url: str, kind: str, count: int) -> None:
        import asyncio

        self.url, self.kind, self.count = url, kind, count
        self.connected = 0
        self.messages = 0
        self.loop = asyncio.new_event_loop()
        self._thread = threading.Thread(target=self.loop.run_forever, daemon=True)
        self._thread.start()
        self._tasks = [
            asyncio.run_coroutine_threadsafe(self._client(), self.loop) for _ in range(count)
        ]
        _wait(lambda: self.connected >= count, 60)

    async def _client(self) -> None:
        import asyncio

        host, port = self.url.removeprefix("http://").split(":")
        if self.kind == "ws":
            from websockets.asyncio.client import connect

            async with connect(self.url.replace("http://", "ws://") + "/ws/status") as ws:
                self.connected += 1
                async for _message in ws:
                    self.messages += 1
            return
        path = "/api/events" if self.kind == "sse" else "/api/camera/stream?fps=30"
        reader, writer = await asyncio.open_connection(host, int(port))
        writer.write(f"GET {path} HTTP/1.1\r\nHost: 127.0.0.1\r\n\r\n".encode())
        await writer.drain()
        self.connected += 1
        while chunk := await reader.read(1 << 16):
            self.messages += chunk.count(b"data: " if self.kind == "sse" else b"--shadowhound")

    def close(self) -> None:
        import asyncio

        async def end() -> None:
            tasks = [t for t in asyncio.all_tasks() if t is not asyncio.current_task()]
            for task in tasks:
                task.cancel()
            await asyncio.gather(*tasks, return_exceptions=True)

        asyncio.run_coroutine_threadsafe(end(), self.loop).result(10)
        self.loop.call_soon_threadsafe(self.loop.stop)
        self._thread.join(5)


class LoadProcess:
    """`Load` in a process of its own, so the clients' work does not share this interpreter
    with the timed requests. `messages` is known after `close()`."""

    def __init__(self, url: str, kind: str, count: int) -> None:
        self.proc = subprocess.Popen(
            [sys.executable, __file__, "--load", kind, "--clients", str(count), "--url", url],
            stdin=subprocess.PIPE,
            stdout=subprocess.PIPE,
            text=True,
        )
        assert self.proc.stdout is not None
        if self.proc.stdout.readline().strip() != "ready":
            raise RuntimeError(f"the {kind} clients did not connect")
        self.messages = 0

    def close(self) -> None:
        assert self.proc.stdin is not None and self.proc.stdout is not None
        self.proc.stdin.close()
        self.messages = int(self.proc.stdout.readline() or 0)
        self.proc.wait(30)


def run_load(url: str, kind: str, count: int) -> None:
    """`--load`: connect the clients, say ready, read until stdin closes, print the count."""
    load = Load(url, kind, count)
    print("ready", flush=True)
    sys.stdin.read()
    messages = load.messages
    load.close()
    print(messages, flush=True)


def load_average() -> float:
    try:
        return os.getloadavg()[0]
    except OSError:
        return float("nan")


class MinimalClient:
    """HTTP/1.1 on one keep-alive socket, each request in one write, as a browser's fetch
    sends it: the e-stop's timed client, so that the round trip measures the server and the
    kernel, not an HTTP library's Python (httpx adds about 1.5 ms; its figure is kept too)."""

    def __init__(self, url: str) -> None:
        host, port = url.removeprefix("http://").split(":")
        self.host = f"{host}:{port}"
        self.sock = socket.create_connection((host, int(port)))
        self.sock.setsockopt(socket.IPPROTO_TCP, socket.TCP_NODELAY, 1)
        self.file = self.sock.makefile("rb")

    def post(self, path: str) -> Any:
        request = f"POST {path} HTTP/1.1\r\nHost: {self.host}\r\nContent-Length: 0\r\n\r\n"
        self.sock.sendall(request.encode())
        status = self.file.readline()
        if not status.startswith(b"HTTP/1.1 200"):
            raise RuntimeError(f"POST {path} answered {status!r}")
        length = 0
        while (line := self.file.readline()) not in (b"\r\n", b""):
            name, _, value = line.partition(b":")
            if name.strip().lower() == b"content-length":
                length = int(value)
        return json.loads(self.file.read(length))

    def close(self) -> None:
        self.file.close()
        self.sock.close()


def bench_estop(runs: int, load: str = "", clients: int = 0) -> dict[str, Any]:
    """E-stop round trips while a mission walks, with `clients` of kind `load` connected (the
    timed client alternates: the minimal client on even stops, httpx on odd ones); then
    GET /api/status at 100 requests/s for 5 s under the same load."""
    server = ServerProcess(time_scale=1.0, camera_fps=30.0 if load == "mjpeg" else 0.0)
    latencies: list[float] = []
    with_httpx: list[float] = []
    to_stop: list[float] = []
    crowd = LoadProcess(server.url, load, clients) if load else None
    minimal = MinimalClient(server.url)
    try:
        with httpx.Client(base_url=server.url, timeout=10) as client:
            for run in range(runs):
                reply = client.post("/api/mission", json={"command": MISSIONS[run % 2]})
                mission_id = reply.json()["mission_id"]
                _wait(lambda: client.get("/api/status").json()["robot"]["moving"])
                time.sleep(random.uniform(0.0, 0.3))
                t0 = time.monotonic()
                if run % 2 == 0:
                    answer = minimal.post("/api/estop")
                    latencies.append((time.monotonic() - t0) * 1e3)
                else:
                    answer = client.post("/api/estop").json()
                    with_httpx.append((time.monotonic() - t0) * 1e3)
                to_stop.append((server.stopped_at() - t0) * 1e3)
                robot = answer["robot"]
                assert robot["estopped"] and not robot["moving"], robot
                _wait(
                    lambda mid=mission_id: (
                        client.get(f"/api/missions/{mid}").json()["state"] == "finished"
                    )
                )
                client.post("/api/estop/release")
            status = _status_latencies(client, 5.0, 100.0)
    finally:
        minimal.close()
        if crowd:
            crowd.close()
        server.close()
    received = crowd.messages if crowd else 0
    return {
        "estop": latencies,
        "httpx": with_httpx,
        "to_stop": to_stop,
        "status": status,
        "received": received,
    }


def _status_latencies(client: httpx.Client, seconds: float, rate: float) -> list[float]:
    """GET /api/status on a fixed schedule while a mission walks."""
    client.post("/api/mission", json={"command": MISSIONS[0]})
    latencies = []
    period, start = 1.0 / rate, time.perf_counter()
    for i in range(int(seconds * rate)):
        pause = start + i * period - time.perf_counter()
        if pause > 0:
            time.sleep(pause)
        t0 = time.perf_counter()
        client.get("/api/status").raise_for_status()
        latencies.append((time.perf_counter() - t0) * 1e3)
    client.post("/api/estop")
    return latencies


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
            with (
                httpx.Client(timeout=10) as client,
                client.stream("GET", server.url + "/api/camera/stream?fps=30") as stream,
            ):
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
    return {"idle": idle * 100, "streaming": busy * 100, "extra": (busy - idle) * 100, "fps": fps}


# -- report ---------------------------------------------------------------------------------


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    parser.add_argument("--quick", action="store_true", help="fewer runs (a smoke test)")
    parser.add_argument("--note", default="", help="a sentence for RESULTS.md (e.g. the load)")
    parser.add_argument(
        "--cases",
        default="idle,sse,ws,mjpeg",
        help="e-stop cases to run, comma-separated: idle, sse, ws, mjpeg",
    )
    parser.add_argument("--repeat", type=int, default=1, help="runs of each e-stop case")
    parser.add_argument("--serve", action="store_true", help=argparse.SUPPRESS)
    parser.add_argument("--time-scale", type=float, default=1.0, help=argparse.SUPPRESS)
    parser.add_argument("--camera-fps", type=float, default=0.0, help=argparse.SUPPRESS)
    parser.add_argument("--load", default="", help=argparse.SUPPRESS)
    parser.add_argument("--clients", type=int, default=0, help=argparse.SUPPRESS)
    parser.add_argument("--url", default="", help=argparse.SUPPRESS)
    args = parser.parse_args()
    if args.load:
        run_load(args.url, args.load, args.clients)
        return
    if args.serve:
        run_server(args.time_scale, args.camera_fps)
        return
    seconds = 3.0 if args.quick else 10.0
    runs = 10 if args.quick else 80  # half of them timed with the minimal client
    scenarios = {
        "idle": ("idle", "", 0),
        "sse": ("200 SSE clients", "sse", 200),
        "ws": ("200 WebSocket clients", "ws", 200),
        "mjpeg": ("3 MJPEG streams at 30 frames/s", "mjpeg", 3),
    }
    cases = [c.strip() for c in args.cases.split(",") if c.strip()]
    unknown = [c for c in cases if c not in scenarios]
    if unknown:
        parser.error(f"unknown case(s) {', '.join(unknown)}; the cases are {', '.join(scenarios)}")
    rows = [estop_row(*scenarios[case], runs, max(1, args.repeat)) for case in cases]
    if "mjpeg" in cases:
        mjpeg = bench_mjpeg(seconds)
        rows.append(
            (
                "MJPEG 30 frames/s to 3 clients: server CPU",
                f"{mjpeg['streaming']:.1f} % of a core",
                "< 15 %",
                f"{mjpeg['extra']:.1f} % above the {mjpeg['idle']:.1f} % of the camera "
                f"feeder alone; {mjpeg['fps']:.1f} frames/s delivered per client",
            )
        )
    for name, value, target, note in rows:
        print(f"{name}: {value} (target {target}; {note})")
    if args.write:
        write(rows, args.note)


def estop_row(
    name: str, load: str, clients: int, runs: int, repeat: int
) -> tuple[str, str, str, str]:
    """`repeat` runs of `runs` stops each on fresh servers: one table row, stops pooled."""
    estop: list[float] = []
    with_httpx: list[float] = []
    to_stop: list[float] = []
    status: list[float] = []
    each = []
    for _ in range(repeat):
        before = load_average()
        measured = bench_estop(runs, load, clients)
        estop += measured["estop"]
        with_httpx += measured["httpx"]
        to_stop += measured["to_stop"]
        status += measured["status"]
        each.append(
            f"p99 {p99(measured['estop']):.2f} ms at load {before:.1f}->"
            f"{load_average():.1f} ({measured['received']} messages to the clients)"
        )
        print(f"  {name}: {each[-1]}", flush=True)
    runs_text = "; ".join(f"run {i + 1}: {text}" for i, text in enumerate(each))
    return (
        f"e-stop round trip, {name}",
        f"{p99(estop):.2f} ms",
        "p99 < 10 ms",
        f"p50 {statistics.median(estop):.2f} ms, p99 {p99(estop):.2f} ms, max "
        f"{max(estop):.2f} ms, {len(estop)} stops (minimal client); with httpx p50 "
        f"{statistics.median(with_httpx):.2f} ms, p99 {p99(with_httpx):.2f} ms, max "
        f"{max(with_httpx):.2f} ms, {len(with_httpx)} stops; request sent to velocity zero p50 "
        f"{statistics.median(to_stop):.2f} ms, p99 {p99(to_stop):.2f} ms, max "
        f"{max(to_stop):.2f} ms; GET /api/status p99 {p99(status):.2f} "
        f"ms (target < 20 ms), max {max(status):.2f} ms over {len(status)}; {runs_text}",
    )


def write(rows: list[tuple[str, str, str, str]], note: str = "") -> None:
    lines = [
        "<!-- web:start -->",
        "## Web dashboard (`bench/bench_web.py`)",
        "",
        f"Measured {time.strftime('%Y-%m-%d')} on this machine (2 cores, shared with other "
        "work), Python " + sys.version.split()[0] + ". The server runs in its own process on "
        "127.0.0.1 with the simulated robot on a real clock; clients are httpx, websockets and, "
        "for the timed e-stops, a minimal HTTP/1.1 client." + (f" {note}" if note else ""),
        "",
        "| measure | result | target | notes |",
        "|---|---|---|---|",
        *[f"| {n} | {v} | {t} | {note} |" for n, v, t, note in rows],
        "",
        "Methods. E-stop: a mission walks; after a random 0-0.3 s the client posts "
        "`/api/estop`, idle or with 200 SSE clients (`/api/events`), 200 WebSocket clients "
        "(`/ws/status`) or 3 MJPEG readers (`/api/camera/stream?fps=30`, camera fed at 30 "
        "frames/s) connected and reading, all from one asyncio loop in a load process of their "
        "own (the WebSocket clients offer permessage-deflate, as browsers do; the server "
        "declines it). Each row pools the stops of its runs, each on a fresh server; its notes "
        "give each run's p99 with the 1-minute load average before and after it. "
        "The e-stop lane (web/estop.py) calls the robot's hard stop before routing, before it "
        "answers, and the answer carries the state read after the stop (checked: stopped and "
        "latched), so the round trip is an upper bound of request-to-stop; it includes the "
        "HTTP parsing on both sides; a real Go2 adds its driver's command latency. "
        "Stops alternate between two timed clients on the same keep-alive connection kind: "
        "a minimal HTTP/1.1 client (the request in one write, the answer read by its "
        "Content-Length; what a browser's fetch does in native code), whose figures are the "
        "row's, and httpx (about 1.5 ms of its own Python per request), listed beside them. "
        "Request sent to velocity zero is measured too: the server's simulated robot prints "
        "when its hard stop has set the velocity to zero, on the clock the client reads "
        "(CLOCK_MONOTONIC, shared by processes on Linux). "
        "Status: after the stops, one keep-alive connection on a fixed 10 ms schedule for 5 s "
        "while a mission walks, under the same clients (which get its events and the 5 Hz "
        "state ticks). MJPEG: a thread in the server process feeds 640x480 JPEG frames (about "
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
