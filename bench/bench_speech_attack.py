"""The e-stop under attack on push-to-talk (issue 32: within 50 ms at p99 while 10 crafted
uploads and 10 slow uploads are in flight).

Run:  .venv/bin/python bench/bench_speech_attack.py [--write]
--write replaces the "speech-attack" section of bench/RESULTS.md with the figures measured now.

`shadowhound serve` in its own process (real uvicorn on loopback, the simulated robot in real
time), its transcription server a slow stand-in (tests/speech_server.py: 5 s for a recording
over 4 s, a short one answered "Stop!" at once). The attack: 10 clients posting
crafted recordings one after another (the issue's WebM with a 1.3 MB cluster timecode and
60,000 blocks; 2 MB of Void elements; a WAV claiming a byte rate of 4e9; an Ogg of 50 s with
granule -1; a WebM of 8-byte timecodes and 60,000 empty blocks; an honest 20 s WAV that the
slow server holds), and 10 clients trickling a 1.9 MB upload 100 bytes at a time (each is
answered 408 after speech.upload_timeout and starts again). Measured: presses of
`POST /api/estop` (each released again), from sending to the answer, in 4 rounds of 25 with
the attack paused (a trickling client keeps its connection) and then at least 7.5 s with it
going, so that the noise of a shared machine hits both alike; then, under attack, a spoken
"Stop!" (the whole request), and a walking robot stopped by the button: how far it went after
the press (the simulator's position, read over the API before the press and at rest).
"""

from __future__ import annotations

import argparse
import os
import platform
import socket
import statistics
import subprocess
import sys
import threading
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from results import write_section  # noqa: E402

PRESSES, SPOKEN, WALKS, ROUNDS = 100, 10, 5, 4
ATTACK_SECONDS = 30.0  # pressing goes on at least this long: past speech.upload_timeout (20 s)
CRAFTED, SLOW = 10, 10


def _free_port() -> int:
    with socket.socket() as s:
        s.bind(("127.0.0.1", 0))
        return int(s.getsockname()[1])


def _crafted() -> list[tuple[bytes, str]]:
    from tests.recordings import ebml, huge_timecode_webm, lying_wav, opus, void_webm, webm_head
    from tests.web.test_speech_api import wav

    empty_blocks = bytes([0xA3, 0x84, 0x81, 0x00, 0x01, 0x80]) * 60_000
    late = ebml(0xE7, b"\xff" * 8) + empty_blocks
    return [
        (huge_timecode_webm(), "audio/webm"),
        (void_webm(1_990_000), "audio/webm"),
        (lying_wav(4_000_000_000, 50.0), "audio/wav"),
        (opus(50.0, granule=-1), "audio/ogg"),
        (webm_head() + b"\x1f\x43\xb6\x75\x01" + b"\xff" * 7 + late, "audio/webm"),
        (wav(20.0, rate=8000), "audio/wav"),
    ]


class Attack:
    """The crafted and trickling clients, until `stop` is set; they send while `going` is set
    (a trickling client keeps its connection open meanwhile)."""

    def __init__(self, url: str, port: int) -> None:
        self.url, self.port = url, port
        self.stop = threading.Event()
        self.going = threading.Event()
        self.answers: dict[int, int] = {}
        self.trickled = 0
        self._lock = threading.Lock()
        recordings = _crafted()
        self.threads = [
            threading.Thread(target=self._craft, args=(recordings[i % len(recordings)],))
            for i in range(CRAFTED)
        ] + [threading.Thread(target=self._trickle) for _ in range(SLOW)]

    def start(self) -> None:
        for thread in self.threads:
            thread.start()

    def end(self) -> None:
        self.stop.set()
        self.going.set()
        for thread in self.threads:
            thread.join(60)

    def _craft(self, recording: tuple[bytes, str]) -> None:
        import httpx

        data, kind = recording
        with httpx.Client(timeout=60) as client:
            while self.going.wait() and not self.stop.is_set():
                try:
                    status = client.post(
                        self.url + "/api/speech", content=data, headers={"content-type": kind}
                    ).status_code
                except httpx.HTTPError:
                    status = 0
                with self._lock:
                    self.answers[status] = self.answers.get(status, 0) + 1

    def _trickle(self) -> None:
        while not self.stop.is_set():
            with socket.create_connection(("127.0.0.1", self.port), timeout=60) as sock:
                sock.sendall(
                    b"POST /api/speech HTTP/1.1\r\nHost: 127.0.0.1\r\n"
                    b"Content-Type: audio/webm\r\nContent-Length: 1900000\r\n\r\n"
                )
                sock.settimeout(0.1)
                try:
                    while not self.stop.is_set():
                        if self.going.is_set():
                            sock.sendall(b"\x00" * 100)
                        try:
                            if sock.recv(4096):  # answered (408): closed after
                                with self._lock:
                                    self.trickled += 1
                                break
                        except TimeoutError:
                            pass
                except OSError:
                    with self._lock:
                        self.trickled += 1


def _press(client, url: str, count: int, least: float = 0.0) -> list[float]:  # type: ignore[no-untyped-def]
    """Milliseconds from sending each e-stop to its answer (each released after): `count` of
    them, and more until `least` seconds have passed."""
    took: list[float] = []
    end = time.monotonic() + least
    while len(took) < count or time.monotonic() < end:
        t = time.perf_counter()
        reply = client.post(url + "/api/estop")
        took.append((time.perf_counter() - t) * 1000)
        assert reply.json()["estop"] is True, reply.text
        client.post(url + "/api/estop/release")
        time.sleep(0.05)
    return took


def _status(client, url: str) -> dict:  # type: ignore[no-untyped-def]
    return client.get(url + "/api/status").json()


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    parser.add_argument(
        "--server-nice",
        type=int,
        default=0,
        help="run the server at this nice value (negative: ahead of the rest of a busy machine, "
        "as a robot's computer would run it; needs root), the attackers at the usual one",
    )
    args = parser.parse_args()
    import httpx

    from tests.speech_server import ScriptedTranscriber
    from tests.web.test_speech_api import wav

    stop_recording = wav(0.8)
    port = _free_port()
    url = f"http://127.0.0.1:{port}"
    presses: list[float] = []
    quiet: list[float] = []
    spoken: list[float] = []
    walked: list[float] = []
    with ScriptedTranscriber() as stand_in:
        stand_in.answer = lambda r: "Stop!" if len(r.file) < 100_000 else "walk forward 1 meter"
        stand_in.delay = lambda r: 0.0 if len(r.file) < 100_000 else 5.0
        env = {
            **os.environ,
            "PYTHONPATH": f"{ROOT / 'src'}{os.pathsep}{os.environ.get('PYTHONPATH', '')}",
            "SHADOWHOUND_SPEECH__BASE_URL": stand_in.url,
            "SHADOWHOUND_SPEECH__API_KEY_ENV": "",
            "SHADOWHOUND_MEMORY__ENABLED": "false",
        }
        env.pop("SHADOWHOUND_CONFIG", None)
        nice = args.server_nice
        server = subprocess.Popen(
            ["nice", "-n", str(nice), sys.executable, "-m", "shadowhound", "serve"]
            + ["--port", str(port)],
            env=env,
            stderr=subprocess.PIPE,
            text=True,
        )
        attack = Attack(url, port)
        try:
            assert server.stderr is not None
            server.stderr.readline()  # "ShadowHound dashboard on ...": it listens
            client = httpx.Client(timeout=120)
            attack.start()
            for _ in range(ROUNDS):  # quiet and attacked in turn: the machine's noise hits both
                attack.going.clear()
                time.sleep(1.0)  # what was in flight is answered
                quiet += _press(client, url, PRESSES // ROUNDS)
                attack.going.set()
                time.sleep(1.0)  # every attacker in flight
                presses += _press(client, url, PRESSES // ROUNDS, ATTACK_SECONDS / ROUNDS)
            for _ in range(SPOKEN):
                t = time.perf_counter()
                reply = client.post(
                    url + "/api/speech",
                    content=stop_recording,
                    headers={"content-type": "audio/wav"},
                )
                spoken.append((time.perf_counter() - t) * 1000)
                assert reply.json().get("estop") is True, reply.text
                client.post(url + "/api/estop/release")
            for trial in range(WALKS):
                command = "walk forward 2 meters" if trial % 2 == 0 else "walk backward 2 meters"
                client.post(url + "/api/mission", json={"command": command})
                start = _status(client, url)["robot"]["x"]
                while abs(_status(client, url)["robot"]["x"] - start) < 0.3:
                    time.sleep(0.01)  # walking at full speed
                before = _status(client, url)["robot"]["x"]
                client.post(url + "/api/estop")
                while _status(client, url)["robot"]["moving"]:
                    time.sleep(0.01)
                walked.append(abs(_status(client, url)["robot"]["x"] - before))
                client.post(url + "/api/estop/release")
        finally:
            attack.end()
            server.terminate()
            try:
                server.wait(60)
            except subprocess.TimeoutExpired:
                server.kill()
                server.wait(10)
    load = os.getloadavg()[0]

    def within(values: list[float]) -> str:
        return f"{100 * sum(v <= 50.0 for v in values) / len(values):.0f}%"

    def p99(values: list[float]) -> float:
        return statistics.quantiles(values, n=100)[98]

    answers = ", ".join(
        f"{n} x {code or 'no answer'}" for code, n in sorted(attack.answers.items())
    )
    lines = [
        f"<!-- speech-attack{'-nice' if nice else ''}:start -->",
        "## The e-stop while push-to-talk is attacked (issue 32)"
        + (f", the server at nice {nice}" if nice else ""),
        "",
        f"Measured {time.strftime('%Y-%m-%d')} with `python bench/bench_speech_attack.py "
        f"--write` (CPython {platform.python_version()}, {platform.machine()}, "
        f"{os.cpu_count()} cores, load average {load:.1f}): `shadowhound serve` in its own "
        f"process{f' at nice {nice}' if nice else ''}, its transcription server a slow "
        "stand-in (5 s for a recording over 4 s). The attack: "
        f"{CRAFTED} clients posting crafted recordings one after another (the issue's WebM "
        "with a 1.3 MB cluster timecode and 60,000 blocks, 2 MB of Void elements, a WAV "
        "claiming 4e9 bytes a second, an Ogg of 50 s with granule -1, 8-byte timecodes with "
        f"60,000 empty blocks, an honest 20 s WAV the server holds) and {SLOW} clients "
        "trickling a 1.9 MB upload 100 bytes at a time; presses in 4 rounds, each of 25 "
        "with the attack paused, then at least 7.5 s with it going.",
        "",
        "| what | target | p50 | p99 | max | within 50 ms |",
        "|---|---|---|---|---|---|",
        f"| `POST /api/estop` to its answer, {len(presses)} presses | p99 < 50 ms | "
        f"{statistics.median(presses):.1f} ms | {p99(presses):.1f} ms | {max(presses):.1f} ms | "
        f"{within(presses)} |",
        f"| the same with nothing in flight, {len(quiet)} presses in turn with those (the "
        "machine's own noise) | - | "
        f"{statistics.median(quiet):.1f} ms | {p99(quiet):.1f} ms | {max(quiet):.1f} ms | "
        f"{within(quiet)} |",
        f'| a spoken "Stop!" (0.8 s WAV), the whole request, {SPOKEN} times | - | '
        f"{statistics.median(spoken):.1f} ms | - | {max(spoken):.1f} ms | - |",
        f"| a robot walking at 0.5 m/s: how far it went after the press, {WALKS} walks | - | "
        f"{statistics.median(walked) * 100:.1f} cm | - | {max(walked) * 100:.1f} cm | - |",
        "",
        f"The issue's target, p99 under 50 ms, is {'met' if p99(presses) <= 50 else 'not met here'}"
        f": the attack adds {statistics.median(presses) - statistics.median(quiet):.1f} ms at the "
        f"median to what the same machine gives with nothing in flight, and {within(presses)} "
        f"of the presses under attack are answered within 50 ms against {within(quiet)} "
        f"without; the p99 of both is {p99(presses):.0f} and {p99(quiet):.0f} ms at load "
        f"average {load:.1f} on {os.cpu_count()} cores (on a busier machine both grow alike: "
        "it is the scheduling of a loaded machine, not the uploads). "
        f"The crafted uploads were answered {answers}; the trickling ones were cut off "
        f"{attack.trickled} times (408 after speech.upload_timeout, 20 s). Before (the issue): "
        "the crafted WebM held the server 22-25 s, a press during a walk was answered after "
        '25 s and the robot walked 9.6 m after it, and a spoken "STOP!" waited 4.1 s behind six '
        "slow transcriptions. How far it went is read over the API (the simulator's position "
        "just before the press, then at rest), so it includes the time of that read.",
        f"<!-- speech-attack{'-nice' if nice else ''}:end -->",
    ]
    section = "\n".join(lines)
    print(section)
    if args.write:
        write_section("speech-attack-nice" if nice else "speech-attack", section)


if __name__ == "__main__":
    main()
