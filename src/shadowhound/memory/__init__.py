"""Memory: persistent mission history and places (SQLite, standard library), and retrieval
memory (Chroma with offline MiniLM embeddings, the `memory` extra, imported lazily)."""

from __future__ import annotations

from .history import MemoryStoreError, MissionHistory
from .places import KnownPlace, PlaceBook, known_places
from .recall import RecallStoreError

__all__ = [
    "KnownPlace",
    "MemoryStoreError",
    "MissionHistory",
    "PlaceBook",
    "RecallStoreError",
    "known_places",
]
