"""Memory: persistent mission history and places (SQLite, standard library), and retrieval
memory (Chroma with offline MiniLM embeddings, the `memory` extra, imported lazily). Every
memory is a robot's (`RobotId`); only the current robot's are goals."""

from __future__ import annotations

from ..errors import ClaimError, MemoryStoreError, RecallStoreError
from ..robot_config import RobotId
from .history import MissionHistory
from .places import KnownPlace, PlaceBook, Places, known_places
from .records import Secondhand, StoredPlace, StoredSighting

__all__ = [
    "ClaimError",
    "KnownPlace",
    "MemoryStoreError",
    "MissionHistory",
    "PlaceBook",
    "Places",
    "RecallStoreError",
    "RobotId",
    "Secondhand",
    "StoredPlace",
    "StoredSighting",
    "known_places",
]
