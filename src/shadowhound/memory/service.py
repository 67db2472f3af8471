"""AgentMemory: what one agent remembers, fed by its events.

History (SQLite) records every mission; taught places live beside it; retrieval memory
(optional) keeps mission summaries, taught facts and observations for semantic search.
Without `memory.enabled`, places last for the process and nothing is written to disk.
A retrieval store that cannot be used (corrupt, a file in its place) turns retrieval memory off
for the run, with a warning and a note in `status()`: memory is an aid, never a reason for a
mission not to run. A broken history database is still an error: it holds the records.
What retrieval memory keeps of a step is the step's skill's to say (`Skill.remembered_as`).

An agent's memory is one robot's (`robot`, a `RobotId`, from the robot's settings): everything it
writes carries that robot, and what it reads as a goal or a hint (places, sightings, recent
missions, retrieval) is that robot's own. Other robots' memories in the same store are history:
`secondhand()` lists them so an answer can say why they are not goals.
"""

from __future__ import annotations

import logging
import re
import time
from pathlib import Path
from typing import Any

from ..config import ShadowHoundConfig
from ..errors import ConfigError, MemoryStoreError, RecallStoreError
from ..events import MissionEvent, MissionFinished, MissionStarted, StepFinished
from ..result import SkillBook, StepStatus
from ..robot_config import RobotId
from .history import MissionHistory
from .places import PlaceBook
from .records import Secondhand, Stored, not_a_goal
from .sightings import SightingBook

log = logging.getLogger(__name__)
_WORD = re.compile(r"[a-z0-9]+")
_STOPWORDS = frozenset(
    (
        "a",
        "an",
        "the",
        "is",
        "are",
        "was",
        "were",
        "i",
        "you",
        "me",
        "my",
        "your",
        "it",
        "in",
        "on",
        "at",
        "to",
        "of",
        "and",
        "or",
        "what",
        "did",
        "do",
        "does",
        "have",
        "has",
        "see",
        "saw",
        "seen",
        "this",
        "that",
        "there",
    )
)


class AgentMemory:
    """History, places and (optionally) recall for one agent. `skills` (the agent's registry)
    say what of their steps retrieval memory keeps (None: only the missions' summaries)."""

    def __init__(
        self,
        settings: ShadowHoundConfig,
        history: MissionHistory | None = None,
        recall: Any = None,
        recall_problem: str | None = None,
        *,
        skills: SkillBook | None = None,
        robot: RobotId | None = None,
    ) -> None:
        self.settings = settings
        self.skills = skills
        self.history = history
        # Whose memory this is: the robot the settings drive, unless the caller names it.
        self.robot = robot if robot is not None else settings.robot.identity
        self.places = PlaceBook(history, robot=self.robot)
        self.sightings = SightingBook(history, robot=self.robot)
        self.recall = recall
        # Why retrieval memory is off although enable_rag asks for it (None: it is not).
        self.recall_problem = recall_problem

    @classmethod
    def open(
        cls,
        settings: ShadowHoundConfig,
        backend: Any = None,
        *,
        skills: SkillBook | None = None,
        robot: RobotId | None = None,
    ) -> AgentMemory:
        """Open what `settings.memory` asks for, as `robot`'s memory (None: the robot the
        settings drive). Raises ConfigError with what to do."""
        cfg = settings.memory
        if not cfg.enabled and not cfg.enable_rag:
            return cls(settings, skills=skills, robot=robot)
        data = Path(cfg.data_dir).expanduser()
        history = None
        if cfg.enabled:
            try:
                history = MissionHistory(data / "history.db")
            except MemoryStoreError as exc:
                raise ConfigError(str(exc)) from exc
            if history.interrupted:
                log.warning(
                    "%d mission(s) were running when the last process stopped; marked interrupted",
                    history.interrupted,
                )
            history.prune(max_age_days=cfg.retention_days, max_missions=cfg.max_missions)
        memory = cls(settings, history, skills=skills, robot=robot)
        if cfg.enable_rag:
            try:
                memory.recall = cls._open_recall(settings, data, backend, memory.robot)
            except RecallStoreError as exc:
                memory.turn_recall_off(exc)
        return memory

    @staticmethod
    def _open_recall(settings: ShadowHoundConfig, data: Path, backend: Any, robot: RobotId) -> Any:
        cfg = settings.memory
        try:
            from .embedding import BackendEmbedder, MiniLMEmbedder
            from .recall import RecallMemory

            if cfg.embedding == "backend":
                if backend is None or not cfg.embedding_model:
                    raise ConfigError(
                        "memory.embedding: backend needs a language-model backend "
                        "and memory.embedding_model"
                    )
                embedder: Any = BackendEmbedder(backend, cfg.embedding_model)
            else:
                embedder = MiniLMEmbedder()
            return RecallMemory(data / "recall", embedder, robot=robot)
        except ImportError as exc:
            raise ConfigError(f"memory.enable_rag is on but {exc}") from exc

    def turn_recall_off(self, exc: RecallStoreError) -> None:
        """Stop using a retrieval store that failed; searches fall back to the history."""
        log.warning("retrieval memory is off for this run: %s", exc)
        self.recall = None
        self.recall_problem = str(exc)

    def status(self) -> dict[str, Any]:
        """For diagnostics: which stores are on, and why retrieval memory is off if it should
        be on."""
        cfg = self.settings.memory
        recall = (
            "on" if self.recall is not None else "unavailable" if self.recall_problem else "off"
        )
        return {
            "robot_id": self.robot.name,
            "history": "on" if self.history is not None else "off",
            "recall": recall,
            "recall_problem": self.recall_problem if cfg.enable_rag else None,
        }

    def close(self) -> None:
        if self.history is not None:
            self.history.close()

    # -- recording (the mission queue) ------------------------------------------------------

    def mission_queued(self, mission_id: str, mission: str) -> None:
        """An interface accepted a mission into its queue: on record before it runs."""
        if self.history is not None:
            self.history.mission_queued(mission_id, mission, time.time(), robot=self.robot)

    def mission_not_run(self, mission_id: str, mission: str, reason: str) -> None:
        """A queued mission ended without starting (dropped, cancelled, refused)."""
        if self.history is not None:
            self.history.mission_not_run(mission_id, mission, reason, time.time(), robot=self.robot)

    def mission_ended(self, record: dict[str, Any]) -> None:
        """A started mission ended outside the agent's own events (the worker's safety net
        after a crash): its record (`MissionResult.to_dict()`) replaces the running row."""
        if self.history is not None:
            self.history.mission_finished(record, time.time(), robot=self.robot)

    # -- recording (agent events) ------------------------------------------------------------

    def on_event(self, event: MissionEvent) -> None:
        if isinstance(event, MissionStarted) and self.history is not None:
            self.history.mission_started(
                event.mission_id, event.mission, event.time, robot=self.robot
            )
        elif isinstance(event, StepFinished) and self.recall is not None:
            step = event.step
            skill = self.skills.find(step.skill) if self.skills is not None else None
            if skill is not None and skill.remembered_as and step.status is StepStatus.SUCCEEDED:
                self._remember_safely(step.output, skill.remembered_as, mission=event.mission_id)
        elif isinstance(event, MissionFinished):
            result = event.result
            if self.history is not None:  # the database keeps the JSON record
                self.history.mission_finished(event.data["result"], event.time, robot=self.robot)
            if self.recall is not None and result.plan is not None:
                robot = result.robot
                summary = f"Mission '{result.mission}' {result.status.value}: {result.response}"
                x, y = (round(robot.x, 4), round(robot.y, 4)) if robot else (0.0, 0.0)
                self._remember_safely(summary, "mission", x=x, y=y, mission=result.mission_id)

    def _remember_safely(self, text: str, kind: str, **meta: Any) -> None:
        recall = self.recall
        if recall is None:
            return
        try:
            recall.add(text[:2000], kind, **meta)
        except RecallStoreError as exc:
            self.turn_recall_off(exc)
        except Exception:  # memory must never break a mission; the history still has it
            log.exception("could not add a %s to retrieval memory", kind)

    # -- reading -----------------------------------------------------------------------------

    def secondhand(self) -> tuple[Secondhand, ...]:
        """The places and sightings in the store that are not this robot's (another robot's,
        or of no known robot), each with why it is not a goal: history, never goals."""
        if self.history is None:
            return ()
        try:
            rows: list[Stored] = [*self.history.every_place(), *self.history.every_sighting()]
        except MemoryStoreError as exc:
            log.error("%s", exc)
            return ()
        return tuple(
            Secondhand(r, not_a_goal(r, self.robot)) for r in rows if r.robot_id != self.robot.name
        )

    def recent_missions(self, limit: int) -> list[dict[str, Any]]:
        """This robot's missions, newest first, from the history database (empty when history
        is off). Missions still waiting in the queue are left out: prompts and chat speak of
        what happened. Other robots' missions are left out too: where another robot went or saw
        something is no hint for this one (`shadowhound history` lists every robot's)."""
        if self.history is None or limit <= 0:
            return []
        try:
            return self.history.recent(limit, queued=False, robot=self.robot)
        except MemoryStoreError as exc:
            log.error("%s", exc)
            return []

    def search(self, query: str, k: int | None = None) -> list[str]:
        """Memories relevant to `query`, as lines, within the prompt budget.

        Semantic with retrieval memory; otherwise shared words with recent missions.
        """
        cfg = self.settings.memory
        k = k or cfg.rag_top_k
        lines = self._semantic_search(query, k)
        if lines is None:
            lines = self._keyword_search(query, k)
        kept, used = [], 0
        for line in lines:
            if used + len(line) > cfg.rag_max_chars:
                break
            kept.append(line)
            used += len(line)
        return kept

    def _semantic_search(self, query: str, k: int) -> list[str] | None:
        """Lines from retrieval memory; None when it is off (or has just turned itself off)."""
        recall = self.recall
        if recall is None:
            return None
        try:
            return [m.line() for m in recall.search(query, k)]
        except RecallStoreError as exc:
            self.turn_recall_off(exc)
            return None

    def _keyword_search(self, query: str, k: int) -> list[str]:
        wanted = set(_WORD.findall(query.lower())) - _STOPWORDS
        if not wanted:
            return []
        scored = []
        for row in self.recent_missions(200):
            text = f"{row['mission']} {row['response'] or ''}"
            overlap = len(wanted & set(_WORD.findall(text.lower())))
            if overlap:
                when = time.strftime("%Y-%m-%d %H:%M", time.localtime(row["started_at"]))
                scored.append(
                    (
                        overlap,
                        row["started_at"],
                        f"[mission, {when}] {row['mission']!r} {row['status']}: "
                        f"{row['response'] or ''}",
                    )
                )
        scored.sort(reverse=True)
        return [line for _, _, line in scored[:k]]
