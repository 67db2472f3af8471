"""RecallMemory: retrieval memory in an embedded Chroma store (the `memory` extra).

It keeps mission summaries, facts people teach ("remember that the fridge is in the kitchen")
and observations (answers of perception.describe, with pose and time). `search` returns the
closest memories by meaning. Vectors come from our own embedder (offline MiniLM, or the
backend's /v1/embeddings) and are handed to Chroma directly, so Chroma never tries to fetch an
embedding model. Telemetry is off.

A store that cannot be used (a corrupt Chroma directory, a file where the directory should be,
no permission) raises `RecallStoreError` naming the path and what to do, at open and at every
later use; `AgentMemory` then turns retrieval memory off for the run instead of failing missions.

A store is opened for one robot (`RobotId`): its memories live in a collection of their own, so a
search finds only that robot's (another robot's notes never reach its planner) at the cost of a
plain nearest-neighbour query. A metadata filter over one shared collection would do the same
but made Chroma scan: 0.2 s a query over 10,000 memories instead of 9 ms. Memories written before
robots were recorded stay in the old, unnamed collection: no robot searches them.
"""

from __future__ import annotations

import hashlib
import threading
import time
import uuid
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any, Protocol

from .. import jsonout
from ..errors import RecallStoreError
from ..robot_config import RobotId

KINDS = ("mission", "fact", "observation")


def _store_error(path: Path, exc: Exception) -> RecallStoreError:
    if path.exists() and not path.is_dir():
        why = "it is a file, not a directory"
    else:
        why = f"{type(exc).__name__}: {exc}"
    return RecallStoreError(
        f"the retrieval memory store {str(path)!r} cannot be used ({why}); move it aside to keep "
        "it for inspection (a new one is created at the next start), or set "
        "memory.enable_rag: false"
    )


class Embedder(Protocol):
    name: str

    def embed(self, texts: list[str]) -> Any: ...


@dataclass(frozen=True)
class Memory:
    """One remembered text. `score` is the cosine similarity to the query (1 = same)."""

    text: str
    kind: str
    created: float
    score: float = 0.0
    meta: dict[str, Any] = field(default_factory=dict)

    def line(self) -> str:
        when = time.strftime("%Y-%m-%d %H:%M", time.localtime(self.created))
        return f"[{self.kind}, {when}] {self.text}"


def collection_name(embedder: Embedder, robot: RobotId | None) -> str:
    """The collection of `robot`'s memories embedded by `embedder` (None: the one of no known
    robot, from before robots were recorded). The name carries the embedder, so vectors of
    different models never mix, and the robot, spelt for Chroma with a hash of its exact name
    (so "go2:robot0" and "go2-robot0" stay apart)."""
    name = "shadowhound-" + "".join(c if c.isalnum() else "-" for c in embedder.name)[:40]
    name = name.strip("-")
    if robot is None:
        return name
    spelt = "".join(c if c.isalnum() else "-" for c in robot.name)[:40]
    return f"{name}-robot-{spelt}-{hashlib.sha256(robot.name.encode()).hexdigest()[:8]}"


class RecallMemory:
    """`robot`'s semantic memory in the store at `path` (a directory). Thread-safe."""

    def __init__(self, path: str | Path, embedder: Embedder, *, robot: RobotId) -> None:
        try:
            import chromadb
            from chromadb.config import Settings
        except ImportError as exc:
            raise ImportError(
                "retrieval memory needs chromadb: pip install 'shadowhound[memory]'"
            ) from exc
        self.path = Path(path).expanduser()
        self.embedder = embedder
        self.robot = robot
        self._lock = threading.Lock()
        # Chroma reports a damaged store with errors of many kinds (its own, sqlite's, OSError
        # from its Rust core); whatever the kind, the store is unusable and the caller must know.
        try:
            self.path.mkdir(parents=True, exist_ok=True)
            client = chromadb.PersistentClient(
                path=str(self.path), settings=Settings(anonymized_telemetry=False)
            )
            self._collection = client.get_or_create_collection(
                collection_name(embedder, robot),
                embedding_function=None,
                metadata={"hnsw:space": "cosine", "robot_id": robot.name},
            )
        except Exception as exc:
            raise _store_error(self.path, exc) from exc

    def add(self, text: str, kind: str, **meta: Any) -> str:
        """Remember `text` as this robot's; `meta` (pose, mission) is kept beside it."""
        if kind not in KINDS:
            raise ValueError(f"memory kind must be one of {', '.join(KINDS)}, got {kind!r}")
        text = text.strip()
        if not text:
            raise ValueError("nothing to remember: the text is empty")
        return self.add_many([(text, kind, meta)])[0]

    def add_many(self, items: list[tuple[str, str, dict[str, Any]]]) -> list[str]:
        ids = [uuid.uuid4().hex for _ in items]
        vectors = self.embedder.embed([text for text, _, _ in items])
        metadatas = [
            {
                "kind": kind,
                "created": time.time(),
                # A position that is not finite (odometry that lies) is left out, not stored.
                **{
                    k: v
                    for k, v in jsonout.finite(meta).items()
                    if isinstance(v, (str, int, float, bool))
                },
                "robot_id": self.robot.name,  # also on each memory, for whoever reads the store
            }
            for _, kind, meta in items
        ]
        with self._lock:
            try:
                self._collection.add(
                    ids=ids,
                    documents=[t for t, _, _ in items],
                    embeddings=list(vectors),
                    metadatas=metadatas,  # type: ignore[arg-type]
                )
            except Exception as exc:
                raise _store_error(self.path, exc) from exc
        return ids

    def search(self, query: str, k: int = 3, kind: str | None = None) -> list[Memory]:
        """This robot's memories closest to `query` (of `kind` when given), closest first."""
        if not query.strip() or k <= 0:
            return []
        vector = self.embedder.embed([query])[0]
        with self._lock:
            try:
                total = self._collection.count()
                if total == 0:
                    return []
                found = self._collection.query(
                    query_embeddings=[vector],
                    n_results=min(k, total),
                    where={"kind": kind} if kind else None,
                    include=["documents", "metadatas", "distances"],
                )
            except Exception as exc:
                raise _store_error(self.path, exc) from exc
        documents = (found.get("documents") or [[]])[0]
        metadatas = (found.get("metadatas") or [[]])[0]
        distances = (found.get("distances") or [[]])[0]
        memories = []
        for text, meta, distance in zip(documents, metadatas, distances, strict=False):
            meta = dict(meta or {})
            created = meta.pop("created", 0.0)
            kind_ = str(meta.pop("kind", "?"))
            meta.pop("robot_id", None)
            created = float(created) if isinstance(created, (int, float)) else 0.0
            memories.append(Memory(text or "", kind_, created, 1.0 - float(distance), meta))
        return memories

    def count(self) -> int:
        with self._lock:
            try:
                return self._collection.count()
            except Exception as exc:
                raise _store_error(self.path, exc) from exc
