"""Memory: persistent mission history and places (SQLite, standard library), and retrieval
memory (Chroma with offline MiniLM embeddings, the `memory` extra, imported lazily)."""

from __future__ import annotations

from ..errors import MemoryStoreError, RecallStoreError
from .history import MissionHistory
from .places import KnownPlace, PlaceBook, Places, known_places

__all__ = [
    "KnownPlace",
    "MemoryStoreError",
    "MissionHistory",
    "PlaceBook",
    "Places",
    "RecallStoreError",
    "known_places",
]
