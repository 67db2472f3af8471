"""Memory benchmarks (issue 7): history insert time and retrieval latency over 10,000 memories.

Run:  .venv/bin/python bench/bench_memory.py [--write] [--memories 10000]
--write replaces the "memory" section of bench/RESULTS.md with the figures measured now.

History: `MissionHistory.mission_finished` with a realistic record (a three-step mission's
`MissionResult.to_dict()`), WAL mode, on the local disk. Retrieval: `RecallMemory.search`
(embed the query with all-MiniLM-L6-v2 in NumPy, then Chroma's HNSW query) over N memories
of all three kinds; the insert of the N memories is timed too.
"""

from __future__ import annotations

import argparse
import random
import statistics
import tempfile
import time
from pathlib import Path

from results import write_section
from shadowhound import RobotAgent, RobotAgentConfig, SimRobot
from shadowhound.memory import MissionHistory, RobotId
from shadowhound.memory.embedding import MiniLMEmbedder
from shadowhound.memory.recall import RecallMemory

ROBOT = RobotId("sim")

THINGS = [
    "fridge",
    "charging dock",
    "red ball",
    "blue box",
    "sofa",
    "door",
    "plant",
    "chair",
    "person",
    "table",
    "window",
    "stairs",
    "cat",
    "shoe",
    "backpack",
    "lamp",
]
ROOMS = ["kitchen", "hallway", "living room", "garage", "office", "bedroom", "garden", "lab"]
TIMES = ["this morning", "at noon", "in the afternoon", "last night", "yesterday", "today"]


def synthetic_memories(n: int) -> list[tuple[str, str, dict[str, object]]]:
    rng = random.Random(7)
    out = []
    for i in range(n):
        thing, room, when = rng.choice(THINGS), rng.choice(ROOMS), rng.choice(TIMES)
        kind = ("fact", "observation", "mission")[i % 3]
        text = {
            "fact": f"the {thing} is usually in the {room}",
            "observation": f"I saw a {thing} in the {room} {when}, about "
            f"{rng.uniform(0.5, 5):.1f} m ahead",
            "mission": f"Mission 'go to the {room}' succeeded {when}: reached the {room}",
        }[kind]
        out.append((text, kind, {"n": i}))
    return out


def bench_history(runs: int = 500) -> list[float]:
    agent = RobotAgent(RobotAgentConfig(robot=SimRobot(time_scale=0.0)))
    record = agent.execute_mission("stand up, walk forward 1 meter and turn left").to_dict()
    with tempfile.TemporaryDirectory() as folder:
        store = MissionHistory(Path(folder) / "history.db")
        times = []
        for i in range(runs):
            record["mission_id"] = f"m{i}"
            t0 = time.perf_counter()
            store.mission_finished(record, time.time(), robot=ROBOT)
            times.append((time.perf_counter() - t0) * 1e3)
        store.close()
    return times


def bench_recall(n: int, queries: int = 200) -> dict[str, float]:
    embedder = MiniLMEmbedder()
    with tempfile.TemporaryDirectory() as folder:
        memory = RecallMemory(Path(folder) / "recall", embedder, robot=ROBOT)
        items = synthetic_memories(n)
        t0 = time.perf_counter()
        for start in range(0, n, 256):
            memory.add_many(items[start : start + 256])
        insert_s = time.perf_counter() - t0
        rng = random.Random(3)
        latencies = []
        for _ in range(queries):
            query = f"where is the {rng.choice(THINGS)}?"
            t0 = time.perf_counter()
            memory.search(query, k=3)
            latencies.append((time.perf_counter() - t0) * 1e3)
        embed_only = []
        for _ in range(50):
            t0 = time.perf_counter()
            embedder.embed(["where is the fridge?"])
            embed_only.append((time.perf_counter() - t0) * 1e3)
        assert memory.count() == n
        latencies.sort()
        return {
            "p50": statistics.median(latencies),
            "p95": latencies[int(0.95 * len(latencies))],
            "embed_p50": statistics.median(embed_only),
            "insert_s": insert_s,
        }


def main() -> None:
    parser = argparse.ArgumentParser(description=__doc__)
    parser.add_argument("--write", action="store_true", help="update bench/RESULTS.md")
    parser.add_argument("--memories", type=int, default=10000)
    args = parser.parse_args()
    history = sorted(bench_history())
    recall = bench_recall(args.memories)
    lines = [
        "<!-- memory:start -->",
        "## Memory (issue 7)",
        "",
        f"Measured {time.strftime('%Y-%m-%d')} with `python bench/bench_memory.py --write`.",
        "",
        "| what | target | measured |",
        "|---|---|---|",
        f"| history insert of a finished mission (SQLite WAL, 500 inserts) | < 2 ms | p50 "
        f"{statistics.median(history):.2f} ms, p95 {history[int(0.95 * len(history))]:.2f} ms |",
        f"| retrieval over {args.memories:,} memories (embed query + Chroma HNSW, top 3, 200 "
        f"queries) | p50 < 20 ms | p50 {recall['p50']:.1f} ms, p95 {recall['p95']:.1f} ms |",
        f"| of which embedding the query (all-MiniLM-L6-v2 in NumPy) | - | p50 "
        f"{recall['embed_p50']:.1f} ms |",
        f"| adding {args.memories:,} memories (batches of 256) | - | {recall['insert_s']:.0f} s |",
        "<!-- memory:end -->",
    ]
    section = "\n".join(lines)
    print(section)
    if args.write:
        write_section("memory", section)


if __name__ == "__main__":
    main()
