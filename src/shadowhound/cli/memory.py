"""The memory commands: `history`, `places` and `recall`.

Memory belongs to robots (docs/memory.md): listings show every robot's missions, places and
sightings labelled with their robot; only "this robot"'s are goals. This robot is the one the
settings drive (`robot.name`, else its type and namespace), or `--robot-name`. `places --claim`
makes a place or sighting of no known robot (from before robots were recorded) this robot's.
"""

from __future__ import annotations

import argparse
import sys
import time
from collections.abc import Callable
from typing import Any

from .. import jsonout
from ..config import ShadowHoundConfig
from ..errors import ClaimError
from ..exit_codes import EXIT_FAILED, EXIT_OK, EXIT_USAGE
from ..memory.places import KnownPlace, known_places, normalize_place
from ..memory.records import StoredPlace, not_a_goal
from ..robot_config import RobotId


def add_memory_commands(sub: Any, common: Callable[[argparse.ArgumentParser], None]) -> None:
    """The `history`, `places` and `recall` commands' arguments, `common` options on each."""
    history = sub.add_parser(
        "history",
        help="list past missions and the objects seen, every robot's, labelled with their "
        "robot, or show one mission (memory.enabled)",
    )
    common(history)
    history.add_argument("mission_id", nargs="?", help="show this mission in full")
    history.add_argument("--limit", type=int, default=20, help="how many to list (default 20)")
    history.add_argument("--json", action="store_true", help="print JSON")

    places = sub.add_parser(
        "places",
        help="list the known places (this robot's goals, other robots' as history), forget "
        "a taught one, or claim one of no known robot",
    )
    common(places)
    _robot_name_option(places)
    what = places.add_mutually_exclusive_group()
    what.add_argument("--forget", metavar="NAME", help="forget a place taught to this robot")
    what.add_argument(
        "--claim",
        metavar="NAME",
        help="make the place and the sighting called NAME of no known robot (kept from "
        "before robots were recorded; never goals) this robot's: say so only if this robot "
        "made them",
    )
    places.add_argument("--json", action="store_true", help="print JSON")

    recall = sub.add_parser(
        "recall", help="search this robot's retrieval memory (memory.enable_rag)"
    )
    common(recall)
    _robot_name_option(recall)
    recall.add_argument("query", help="what to look for, e.g. 'where is the fridge?'")


def _robot_name_option(parser: argparse.ArgumentParser) -> None:
    parser.add_argument(
        "--robot-name",
        metavar="ROBOT",
        default=None,
        help="the robot whose memory this is (default: the profile's robot: robot.name, else "
        "its type and namespace, e.g. sim, go2, go2:robot0)",
    )


def _this_robot(args: argparse.Namespace, settings: ShadowHoundConfig) -> RobotId:
    """The robot whose memory the command reads as its own. Raises ConfigError on a bad name."""
    from ..errors import ConfigError

    name = getattr(args, "robot_name", None)
    if not name:
        return settings.robot.identity
    try:
        return RobotId(name)
    except ValueError as exc:
        raise ConfigError(f"--robot-name: {exc}") from exc


def _memory(settings: ShadowHoundConfig, robot: RobotId | None = None) -> Any:
    from ..memory.service import AgentMemory

    return AgentMemory.open(settings, robot=robot)


def _when(seconds: float) -> str:
    return time.strftime("%Y-%m-%d %H:%M:%S", time.localtime(seconds))


def _label(robot_id: str | None) -> str:
    return "(no known robot)" if robot_id is None else robot_id


def cmd_history(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    if not settings.memory.enabled:
        print("shadowhound: mission history is off (memory.enabled: false)", file=sys.stderr)
        return EXIT_USAGE
    memory = _memory(settings)
    assert memory.history is not None
    try:
        _note_rejected(memory.history)
        if args.mission_id:
            record = memory.history.get(args.mission_id)
            if record is None:
                print(
                    f"shadowhound: no mission {args.mission_id!r} in {memory.history.path}",
                    file=sys.stderr,
                )
                return EXIT_FAILED
            jsonout.dump(record, sys.stdout, indent=2, default=str)
            sys.stdout.write("\n")
            return EXIT_OK
        rows = memory.history.recent(max(1, args.limit))
        if args.json:
            jsonout.dump(rows, sys.stdout, indent=2)
            sys.stdout.write("\n")
            return EXIT_OK
        for row in rows:
            print(
                f"{row['id']}  {_when(row['started_at'])}  {row['status']:<11} "
                f"{_label(row['robot_id']):<16} {row['mission'][:60]!r}"
            )
        seen = memory.history.every_sighting()
        if seen:
            print("objects seen (the latest sighting of each by each robot, world frame):")
        for s in seen:
            print(
                f"  {s.name:<20} x={s.x:7.2f} y={s.y:7.2f}  {_when(s.seen_at)}  confidence "
                f"{s.confidence:.2f}  seen by {_label(s.robot_id)}"
            )
        return EXIT_OK
    finally:
        memory.close()


def _note_rejected(history: Any) -> None:
    """One line on stderr when the history has set records aside (see docs/memory.md)."""
    count = history.rejected_count()
    if count:
        print(
            f"shadowhound: note: {count} record(s) the history database refused are set "
            f"aside in {history.rejected} (one JSON line each, with the error)",
            file=sys.stderr,
        )


def cmd_places(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:

    robot = _this_robot(args, settings)
    memory = _memory(settings, robot)
    try:
        if args.forget:
            if not memory.places.forget(args.forget):
                print(
                    f"shadowhound: robot {robot.name!r} has no taught place {args.forget!r}",
                    file=sys.stderr,
                )
                return EXIT_FAILED
            print(f"forgot {args.forget!r}")
            return EXIT_OK
        if args.claim:
            return _claim(memory, robot, normalize_place(args.claim))
        mine = known_places(settings.places, memory.places)
        theirs = [o.record for o in memory.secondhand() if isinstance(o.record, StoredPlace)]
        if args.json:
            jsonout.dump(_place_rows(mine, theirs, robot), sys.stdout, indent=2)
            sys.stdout.write("\n")
            return EXIT_OK
        for name, p in mine.items():
            print(f"{name:<20} x={p.x:7.2f} y={p.y:7.2f}  {p.source}")
        if theirs:
            print(f"taught to other robots (history, never goals for robot {robot.name!r}):")
        for t in theirs:
            print(f"  {t.name:<18} x={t.x:7.2f} y={t.y:7.2f}  taught to {_label(t.robot_id)}")
        if any(t.robot_id is None for t in theirs):
            print(
                "  (no known robot: taught before robots were recorded; if this robot was taught "
                "it, claim it: shadowhound places --claim NAME [--robot-name ROBOT])"
            )
        return EXIT_OK
    finally:
        memory.close()


def _place_rows(
    mine: dict[str, KnownPlace], theirs: list[StoredPlace], robot: RobotId
) -> list[dict[str, Any]]:
    """Every place as `places --json` lists it: this robot's goals (`goal` true), then other
    robots' (history: `goal` false, `robot_id` whose, null for no known robot)."""
    rows: list[dict[str, Any]] = [
        {
            "name": name,
            "x": p.x,
            "y": p.y,
            **({} if p.yaw is None else {"yaw": p.yaw}),
            "source": p.source,
            "robot_id": None if p.source == "profile" else robot.name,
            "goal": True,
        }
        for name, p in mine.items()
    ]
    rows += [
        {
            "name": t.name,
            "x": t.x,
            "y": t.y,
            "yaw": t.yaw,
            "source": "taught",
            "robot_id": t.robot_id,
            "goal": False,
            "why": not_a_goal(t, robot),
        }
        for t in theirs
    ]
    return rows


def _claim(memory: Any, robot: RobotId, name: str) -> int:
    if memory.history is None:
        print(
            "shadowhound: nothing to claim: the mission history is off (memory.enabled: false)",
            file=sys.stderr,
        )
        return EXIT_USAGE
    try:
        claimed = memory.history.claim(robot, name)
    except ClaimError as exc:
        print(f"shadowhound: {exc}", file=sys.stderr)
        return EXIT_FAILED
    print(f"claimed the {name} ({' and '.join(claimed)}) for robot {robot.name!r}")
    return EXIT_OK


def cmd_recall(args: argparse.Namespace, settings: ShadowHoundConfig) -> int:
    memory = _memory(settings, _this_robot(args, settings))
    try:
        # Missions carry on without a broken store (it turns itself off); this command exists
        # to search it, so it says what is wrong instead of answering from elsewhere.
        found = [] if memory.recall_problem else memory.search(args.query)
        if memory.recall_problem:
            print(
                f"shadowhound: retrieval memory is unavailable: {memory.recall_problem}",
                file=sys.stderr,
            )
            return EXIT_USAGE
        print("\n".join(found) if found else "nothing remembered about that")
        return EXIT_OK
    finally:
        memory.close()
