"""Honest Go2 missions over DDS on a loaded machine (issue 32): how many fail, and how.

Run:  .venv/bin/python bench/bench_false_failures.py [--missions N] [--hogs N] [--label L]
      [--write] [--json FILE]
      .venv/bin/python bench/bench_false_failures.py --saved LABEL=FILE [--saved ...]
Needs rclpy, shadowhound_interfaces, go2_interfaces and vision_msgs (bash scripts/build_ros.sh).
DDS stays on loopback (the project's Fast DDS profile, LOCALHOST discovery, a domain id this
process holds). --write puts this run's row (under `--label`, e.g. "after, run 1") into the
"false-failures" section of bench/RESULTS.md, keeping the rows of other labels; --json saves the
run's records, and --saved writes saved runs (before and after a change: each its own checkout).

Method. As tests/ros/test_go2_coco.py runs them: `shadowhound sim-driver --detector coco` (the
simulated Go2 as go2_ros2_sdk behaves, its camera's COCO boxes on `detected_objects`) and
`shadowhound node -p robot:=go2 -p coco_detections_topic:=detected_objects` as their own
processes (their defaults: the watchdog at 0.25 s), beside `--hogs` CPU hogs
(pure-Python busy loops at nice 0). The node runs a fixed round of honest missions, over and over
(turns of 90 and 180 degrees, walks of 1 to 2 m forward and back, "go to x=0, y=0" through the
driver's Nav2): the driver never lies. Each mission is judged by the driver's truth (start and
end at rest): it did what was asked when it ended within the step's outcome tolerance (5 degrees,
0.10 m). A failed mission is a false failure: the robot is honest; the truth says whether it had
in fact done what was asked. Failures are grouped by the words of their reason.
"""

from __future__ import annotations

import argparse
import contextlib
import json
import math
import os
import platform
import re
import shutil
import signal
import subprocess
import sys
import tempfile
import time
from collections import Counter
from datetime import date
from pathlib import Path
from typing import Any

from shadowhound.ros.dds import claim_domain, loopback_env

_DOMAIN, _HELD = claim_domain()  # held for this process's life: no other run meets it
os.environ.update(loopback_env(_DOMAIN))  # before rclpy is imported

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))  # tests.ros: the rig the ROS tests run missions on

from results import RESULTS, write_section  # noqa: E402
from tests.home import home_env  # noqa: E402
from tests.ros.rosclient import RosClient  # noqa: E402
from tests.ros.test_go2_truth import frame_of, start_rig  # noqa: E402

SECTION = "false-failures"
# (mission, what the truth must show: ("turn", degrees) | ("walk", metres) | ("at", x, y))
ROUND: list[tuple[str, tuple[Any, ...]]] = [
    ("turn left 90 degrees", ("turn", 90.0)),
    ("walk forward 1 meter", ("walk", 1.0)),
    ("turn right 180 degrees", ("turn", -180.0)),
    ("walk forward 2 meters", ("walk", 2.0)),
    ("turn left 90 degrees", ("turn", 90.0)),
    ("walk backward 1 meter", ("walk", -1.0)),
    ("go to x=0, y=0", ("at", 0.0, 0.0)),
    ("turn right 90 degrees", ("turn", -90.0)),
    ("walk forward 1.5 meters", ("walk", 1.5)),
    ("go to x=0, y=0", ("at", 0.0, 0.0)),
]
METRES, DEGREES = 0.10, 5.0  # safety.outcome_tolerance, outcome_tolerance_deg
KINDS = [  # the words that name a failure's kind, most specific first
    ("odometry disagrees (check at rest)", r"odometry shows the (leg|turn) done"),
    ("stopped short: commands' bound", r"stopped .* short of the (goal|turn)"),
    ("no odometry (stale)", r"no odometry on"),
    ("odometry not trusted", r"odometry is not trusted"),
    ("watchdog", r"watchdog"),
    ("no progress", r"no progress for"),
    ("timed out", r"timed out"),
]
HOG = "while True:\n    pass\n"


def kind_of(final: str) -> str:
    return next((name for name, words in KINDS if re.search(words, final)), "other")


def did_as_asked(want: tuple[Any, ...], start: dict[str, Any], end: dict[str, Any]) -> str:
    """'' when the truth shows what was asked, within the outcome tolerance; else what it shows."""
    ahead, left, turned = frame_of(start, end)
    if want[0] == "turn":
        off = abs(math.remainder(math.radians(turned - want[1]), math.tau))
        ok = math.degrees(off) <= DEGREES
        return "" if ok else f"turned {turned:.1f} degrees"
    if want[0] == "walk":
        off = math.hypot(ahead - want[1], left)
        return "" if off <= METRES else f"{ahead:.2f} m ahead, {left:.2f} m left"
    off = math.hypot(end["x"] - want[1], end["y"] - want[2])
    return "" if off <= METRES else f"at ({end['x']:.2f}, {end['y']:.2f})"


def start_processes(client: RosClient, keep: set[int], attempts: int = 3) -> tuple[Any, Any]:
    """The driver and the node, as test_go2_coco starts them. On a machine this loaded a start
    may not be ready within the tests' 30 s: then its processes (this one's children but
    `keep`) are killed and it starts again."""
    for attempt in range(attempts):
        try:
            return start_rig(
                client,
                ("--detector", "coco"),
                "/honest",
                "/honest",
                "honest",
                "-p",
                "coco_detections_topic:=detected_objects",
                "-p",
                "camera_x:=0.0",
            )
        except AssertionError as exc:
            for pid in children() - keep:
                with contextlib.suppress(ProcessLookupError):
                    os.kill(pid, signal.SIGKILL)
            print(f"start {attempt + 1} failed: {str(exc)[:200]}", flush=True)
    raise SystemExit("bench_false_failures: the driver and node did not start")


def children() -> set[int]:
    """The pids of this process's children still running."""
    found = set()
    for status in Path("/proc").glob("[0-9]*/status"):
        with contextlib.suppress(OSError):
            for line in status.read_text().splitlines():
                if line.startswith("PPid:") and line.split()[1] == str(os.getpid()):
                    found.add(int(status.parent.name))
    return found


def run(missions: int, hogs: int) -> dict[str, Any]:
    home = tempfile.mkdtemp(prefix="bench-false-failures-home-")
    os.environ.update(home_env(Path(home)))  # the node's history stays out of the user's home
    hog_procs = [subprocess.Popen([sys.executable, "-c", HOG]) for _ in range(hogs)]
    client = RosClient("bench_false_failures_client")
    records: list[dict[str, Any]] = []
    began = time.monotonic()
    stop = None
    try:
        rig, stop = start_processes(client, {p.pid for p in hog_procs})
        load = []
        for i in range(missions):
            mission, want = ROUND[i % len(ROUND)]
            start = rig.truth.still()
            final = rig.agent.run(mission, 120.0)
            end = rig.truth.still()
            load.append(os.getloadavg()[0])
            ok = final.startswith("COMPLETED: ")
            record = {
                "mission": mission,
                "ok": ok,
                "final": final,
                "truth": did_as_asked(want, start, end),
                "start": {k: start[k] for k in ("x", "y", "yaw")},
                "end": {k: end[k] for k in ("x", "y", "yaw")},
            }
            records.append(record)
            mark = "ok " if ok else "FAIL"
            print(f"{i + 1:3d} {mark} {mission:26s} truth: {record['truth'] or 'as asked'}")
            if not ok:
                print(f"     {final}", flush=True)
                record["log"] = rig.node.output()[-4000:]
            if not ok and end["moving"]:
                rig.truth.still()
    finally:
        if stop is not None:
            stop()
        client.close()
        for p in hog_procs:
            p.kill()
            p.wait()
        shutil.rmtree(home, ignore_errors=True)
    return {
        "records": records,
        "seconds": time.monotonic() - began,
        "load": sum(load) / len(load) if load else 0.0,
        "hogs": hogs,
    }


def row(label: str, result: dict[str, Any]) -> str:
    records = result["records"]
    failed = [r for r in records if not r["ok"]]
    kinds = Counter(kind_of(r["final"]) for r in failed)
    truly = sum(1 for r in failed if not r["truth"])
    wrong = sum(1 for r in records if r["ok"] and r["truth"])
    by_kind = ", ".join(f"{k}: {n}" for k, n in kinds.most_common()) or "-"
    return (
        f"| {label} | {len(records)} | {len(failed)} ({100 * len(failed) / len(records):.1f} %) "
        f"| {truly} | {by_kind} | {wrong} | {result['hogs']} | {result['load']:.1f} |"
    )


def write(runs: dict[str, dict[str, Any]]) -> None:
    """Put `runs` (label -> result) into the section, keeping the rows of other labels."""
    text = RESULTS.read_text() if RESULTS.exists() else ""
    start, end = f"<!-- {SECTION}:start -->", f"<!-- {SECTION}:end -->"
    old = text.split(start, 1)[1].split(end, 1)[0] if start in text else ""
    ours = tuple(f"| {label} |" for label in runs) + tuple(f"- {label}: " for label in runs)
    kept = [line for line in old.splitlines() if not line.startswith(ours)]
    rows = [line for line in kept if line.startswith("| ") and not line.startswith("| run ")]
    rows += [row(label, result) for label, result in runs.items()]
    failures = [line for line in kept if line.startswith("- ")]
    failures += [
        f"- {label}: `{r['mission']}`: {r['final'][:200]}... (truth: {r['truth'] or 'as asked'})"
        for label, result in runs.items()
        for r in result["records"]
        if not r["ok"]
    ]
    section = f"""{start}
## Honest Go2 missions on a loaded machine (issue 32, `bench/bench_false_failures.py`)

Measured {date.today().isoformat()} with `python bench/bench_false_failures.py --label LABEL
--write` (CPython {platform.python_version()}, {platform.machine()}, {os.cpu_count()} cores,
nothing else running; ROS 2 Jazzy rclpy from PyPI, Fast DDS on shared memory / loopback);
"before" is the code before issue 32's fix (57af3de, run from its own checkout), "after" with it.

`shadowhound sim-driver --detector coco` and `shadowhound node -p robot:=go2` (with the
detector's boxes; every setting at its default, the watchdog at 0.25 s) as their own processes, as
tests/ros/test_go2_coco.py runs them, beside two pure-Python CPU hogs at nice 0; a round of
honest missions over and over (turns of 90 and 180 degrees, walks of 1 to 2 m forward and back,
"go to x=0, y=0" through the driver's Nav2). The driver never lies: every failed mission is a
failure of an honest robot. "Did it anyway" counts the failed missions the driver's truth shows
within the outcome tolerance of what was asked (5 degrees, 0.10 m): false failures in the
strict sense; "wrong successes" the missions that reported success with the truth outside it.
Load: the 1-minute load average (2 cores), mean over the missions; the hogs make about 2 of it,
the driver, the node and the bench the rest.

| run | missions | failed | did it anyway | failures by kind | wrong successes | hogs | load |
|---|---|---|---|---|---|---|---|
{chr(10).join(sorted(rows))}

{chr(10).join(sorted(failures)) or "No failures."}
{end}
"""
    write_section(SECTION, section)


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--missions", type=int, default=50)
    parser.add_argument("--hogs", type=int, default=2)
    parser.add_argument("--label", default="run")
    parser.add_argument("--write", action="store_true")
    parser.add_argument("--json", type=Path, help="also save every mission's record here")
    parser.add_argument(
        "--saved",
        action="append",
        default=[],
        metavar="LABEL=JSON",
        help="write a run saved with --json under LABEL instead of running one",
    )
    args = parser.parse_args()
    if args.saved:
        runs = {}
        for item in args.saved:
            label, path = item.split("=", 1)
            runs[label] = json.loads(Path(path).read_text())
        write(runs)
        return
    result = run(args.missions, args.hogs)
    print(row(args.label, result))
    if args.json:
        args.json.write_text(json.dumps(result, indent=1))
    if args.write:
        write({args.label: result})


if __name__ == "__main__":
    main()
