"""What the history database holds of places and sightings, each labelled with its robot.

A row's `robot_id` is the robot that taught the place or saw the object (`RobotId.name`), or
None for a row from before robots were recorded. Only the current robot's own rows are ever
goals (the history reads them with `load_places(robot)` and `load_sightings(robot)`); these
records are every robot's, for listings and for saying why a name is not a goal.
"""

from __future__ import annotations

from dataclasses import dataclass

from ..robot_config import RobotId

CLAIM_HINT = "shadowhound places --claim"


@dataclass(frozen=True)
class StoredPlace:
    """A taught place as stored: whose, its name, pose (world frame) and when it was taught."""

    robot_id: str | None
    name: str
    x: float
    y: float
    yaw: float
    created_at: float

    kind = "place"


@dataclass(frozen=True)
class StoredSighting:
    """The latest sighting of an object by one robot, as stored."""

    robot_id: str | None
    name: str
    x: float
    y: float
    radius: float
    confidence: float
    stamp: float
    seen_at: float

    kind = "object"


Stored = StoredPlace | StoredSighting


def whose(record: Stored) -> str:
    """Whose memory it is, as a listing says it: "robot 'sim'", or "no known robot"."""
    return "no known robot" if record.robot_id is None else f"robot {record.robot_id!r}"


def not_a_goal(record: Stored, robot: RobotId) -> str:
    """Why `robot` does not go to what another robot (or no known robot) remembers."""
    name = record.name.removeprefix("the ")
    made = "taught" if isinstance(record, StoredPlace) else "seen"
    if record.robot_id is None:
        return (
            f"the {name} was {made} before robots were recorded, by no known robot: not a goal "
            f"until a person claims it for this robot ({CLAIM_HINT} {name!r} --robot-name "
            f"{robot.name})"
        )
    return f"the {name} was {made} by robot {record.robot_id!r}, not by this robot: not a goal"


@dataclass(frozen=True)
class Secondhand:
    """Another robot's memory (or one of no known robot) as the current robot sees it: the
    record, and why it is not a goal here (`not_a_goal`)."""

    record: Stored
    note: str

    @property
    def name(self) -> str:
        return self.record.name
