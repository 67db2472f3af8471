"""Every exception ShadowHound raises on purpose, in one tree. Messages are for people: each says
what was wrong and what is allowed or what to do.

    ShadowHoundError                 the root: catch it to catch anything below
    |
    +-- ConfigError                  configuration: a profile, file, option or value is wrong
    |   +-- ParameterError           ... a ROS parameter of the node
    |   +-- BackendUnavailable       ... the language-model server does not answer or lacks the
    |                                    model (the start-up check); also a BackendError
    +-- BackendError                 backend: a request to the language model failed
    |   +-- BackendCancelled         ... the mission was cancelled while the model was asked
    |   +-- BackendUnavailable       ... (see above)
    +-- PlanningError                planning: the request could not be turned into a plan
    +-- NotUnderstood                ... one clause the offline planner cannot plan (it becomes
    |                                    part of a PlanningError; never leaves the planner)
    +-- SkillValidationError         plan checking: a proposed skill call is malformed (ValueError)
    +-- RobotError                   robot: the robot refused or failed a command
    +-- SkillError                   a skill could not do what it was asked
    |   +-- SkillTimeout             ... it ran past its time-out
    |   +-- Relocalized              ... SLAM corrected the map pose during a leg: it stopped
    +-- SafetyError                  safety: a step refused or a mission stopped for safety
    |   +-- PlanProblem              ... a step cannot be done here: a limit, the geofence, an
    |   |                                unknown place (the governor's refusals; ValueError)
    |   +-- MissionCancelled         ... cancel or e-stop stopped the running skill
    |   +-- WatchFired               ... a watched condition held: the step stopped (until:
    |                                    the step is done; unless: the mission ends there)
    +-- DetectionError               ros: a detection message that cannot be used (ValueError)
    +-- PlanError                    world: no safe path to the goal
    +-- GridError                    world: a map or grid query is malformed (ValueError)
    +-- TransformUnavailable         robot: a frame transform not known at the time asked
    |                                    (LookupError)
    +-- UnitError                    a value is not a quantity of the kind asked (ValueError)
    +-- MemoryStoreError             memory: the history database cannot be used
    |   +-- RecallStoreError         ... the retrieval store cannot be used
    +-- PlaceError                   memory: a place without a name or a finite position
    |                                    (ValueError)
    +-- ClaimError                   memory: a claim of a memory of no known robot that
    |                                    cannot be made (ValueError)
    +-- CaseFileError                evaluation: a mission-case file is malformed (ValueError)
    +-- UsageError                   cli: a command line argparse cannot parse
    +-- ServeError                   web/mcp: a server cannot start as asked
    +-- NodeNotFound                 ros client: nothing on the ROS graph answers (no mission
    |                                    node, no e-stop subscriber) within the wait
    +-- FrameUnavailable             web: no camera frame to show yet
    +-- ToolInputError               mcp: arguments a tool cannot take (ValueError)
    +-- AudioProblem                 hearing: a recording that cannot be used (ValueError)
    |   +-- RecordingTooLong         ... it is longer than speech.max_seconds
    |   +-- RecordingUnreadable      ... its bytes are not a recording of the kind it says
    +-- TranscriptionError           hearing: the transcription server failed (its `status`)
    +-- HearingBusy                  hearing: too many recordings at once, this one not heard
                                         (its `status`: 429 pushed out, 503 waited too long)

Classes that were ValueErrors stay ValueErrors (pydantic validators and callers rely on it).
Callers catch by class, never by comparing class names. Each class is also importable from the
module where it is raised (e.g. `shadowhound.config.ConfigError`); it is the same class.
This module imports only `usage` (what a failed plan cost), so any module may import it.
"""

from __future__ import annotations

from .usage import Usage

__all__ = [
    "AudioProblem",
    "BackendCancelled",
    "BackendError",
    "BackendUnavailable",
    "CaseFileError",
    "ClaimError",
    "ConfigError",
    "DetectionError",
    "FrameUnavailable",
    "GridError",
    "HearingBusy",
    "MemoryStoreError",
    "MissionCancelled",
    "NodeNotFound",
    "NotUnderstood",
    "ParameterError",
    "PlanError",
    "PlaceError",
    "PlanProblem",
    "PlanningError",
    "RecallStoreError",
    "RecordingTooLong",
    "RecordingUnreadable",
    "Relocalized",
    "RobotError",
    "SafetyError",
    "ServeError",
    "ShadowHoundError",
    "SkillError",
    "SkillTimeout",
    "SkillValidationError",
    "ToolInputError",
    "TranscriptionError",
    "TransformUnavailable",
    "UnitError",
    "UsageError",
    "WatchFired",
]


class ShadowHoundError(Exception):
    """Anything ShadowHound raises on purpose. The message is for people."""


# -- configuration ---------------------------------------------------------------------------


class ConfigError(ShadowHoundError):
    """A profile, file or value is wrong. The message says which and what is allowed."""


class ParameterError(ConfigError):
    """One or more ROS parameters are invalid. The message lists each and what is allowed."""


# -- backend ---------------------------------------------------------------------------------


class BackendError(ShadowHoundError):
    """A request to the language model failed. The message is for people."""

    def __init__(self, message: str, status: int | None = None) -> None:
        super().__init__(message)
        self.status = status


class BackendCancelled(BackendError):
    """The mission was cancelled while waiting on the model; the request was abandoned."""


class BackendUnavailable(ConfigError, BackendError):
    """The start-up check failed: the server does not answer or does not have the model.

    A configuration error first (the fix is in the profile or the server; `shadowhound` exits 2),
    and a backend error too.
    """


# -- planning and plan checking --------------------------------------------------------------


class PlanningError(ShadowHoundError):
    """The planner could not turn the request into a plan. The message is for people."""

    def __init__(
        self,
        message: str,
        *,
        understood: list[str] | None = None,
        not_understood: list[str] | None = None,
        usage: Usage | None = None,
    ) -> None:
        super().__init__(message)
        self.message = message
        self.understood = understood or []
        self.not_understood = not_understood or []
        self.usage = usage if usage is not None else Usage()


class NotUnderstood(ShadowHoundError):
    """A clause of a known kind that cannot be planned; the reason is shown to the user."""

    def __init__(self, reason: str = "") -> None:
        super().__init__(reason)
        self.reason = reason


class SkillValidationError(ShadowHoundError, ValueError):
    """A proposed skill call is not valid. `problems` are single sentences for people."""

    def __init__(self, problems: list[str]) -> None:
        super().__init__("; ".join(problems))
        self.problems = problems


# -- robot and skills ------------------------------------------------------------------------


class RobotError(ShadowHoundError):
    """The robot refused or failed a command. The message is for people."""


class SkillError(ShadowHoundError):
    """A skill could not do what it was asked. The message is for people."""


class Relocalized(SkillError):
    """Localization corrected the robot's map pose while a leg ran (SLAM's map -> odom jumped):
    the leg stopped rather than walk on the old transform. A walk to a goal plans again from
    the corrected pose; a relative move ends here."""


class SkillTimeout(SkillError):
    """A skill ran past its time-out on the robot's clock."""


# -- safety ----------------------------------------------------------------------------------


class SafetyError(ShadowHoundError):
    """A step was refused, or a mission stopped, to keep the robot and people safe."""


class PlanProblem(SafetyError, ValueError):
    """A step is valid in form but cannot be done here (unknown place, limit exceeded)."""


class MissionCancelled(SafetyError):
    """The mission was cancelled or the e-stop was pressed while a skill ran."""


# -- world model, units ----------------------------------------------------------------------


class WatchFired(SafetyError):
    """A step's watched condition held (`watch`, a plan.Watch): the robot was stopped.
    `observed` says what was seen ("red ball seen 2.3 m away")."""

    def __init__(self, watch: object, observed: str) -> None:
        super().__init__(observed)
        self.watch = watch
        self.observed = observed


class PlanError(ShadowHoundError):
    """No safe path: the message says why (goal blocked, off the map, no way through)."""


class DetectionError(ShadowHoundError, ValueError):
    """One detection could not be used; the message says what was wrong and what is allowed."""


class GridError(ShadowHoundError, ValueError):
    """A map or a grid query was malformed. The message says what is allowed."""


class TransformUnavailable(ShadowHoundError, LookupError):
    """A frame transform asked of the TF tree is unknown: a frame nobody published, frames in
    two trees, or a time outside the history kept. The message says which and what is known."""


class UnitError(ShadowHoundError, ValueError):
    """A value could not be read as a quantity of the kind asked for; the message says why."""


# -- memory, evaluation ----------------------------------------------------------------------


class MemoryStoreError(ShadowHoundError):
    """The history database cannot be used. The message names the file and what to do."""


class RecallStoreError(MemoryStoreError):
    """The retrieval store cannot be used. The message names the path and what to do."""


class PlaceError(ShadowHoundError, ValueError):
    """A place cannot be kept: it has no name, or its position is not finite numbers."""


class ClaimError(ShadowHoundError, ValueError):
    """A memory of no known robot cannot be claimed for this one: there is none by that name,
    or the robot has its own. The message says what can be claimed."""


class CaseFileError(ShadowHoundError, ValueError):
    """The case file is not in the mission-case format. The message says where and why."""


# -- interfaces ------------------------------------------------------------------------------


class UsageError(ShadowHoundError):
    """A command line argparse cannot parse; `usage` is the failing (sub)command's usage."""

    def __init__(self, message: str, usage: str) -> None:
        super().__init__(message)
        self.usage = usage


class ServeError(ShadowHoundError):
    """The server cannot start as asked. The message says why and what to do."""


class NodeNotFound(ShadowHoundError):
    """Nothing on this ROS graph answers what the client sends (see ros/client.py). The message
    says what was looked for and which ROS settings to compare."""


class FrameUnavailable(ShadowHoundError):
    """No frame yet, or one that cannot be shown. The message says which."""


class ToolInputError(ShadowHoundError, ValueError):
    """Arguments a tool cannot take. The message says what was wrong and what is allowed."""


class AudioProblem(ShadowHoundError, ValueError):
    """A recording that cannot be used; the message says why and what is allowed."""


class RecordingTooLong(AudioProblem):
    """A recording longer than it may be: `seconds` (as far as it was read, unless `exact`)
    against `limit`."""

    def __init__(self, seconds: float, limit: float, *, exact: bool) -> None:
        shown = f"{seconds:.0f}" if seconds < 1e7 else f"{seconds:.2g}"
        said = f"{shown} s long" if exact else f"longer than {limit:g} s"
        super().__init__(
            f"the recording is {said}; at most {limit:g} s are taken (speech.max_seconds): "
            "hold the button for one short request"
        )
        self.seconds, self.limit, self.exact = seconds, limit, exact


class RecordingUnreadable(AudioProblem):
    """A recording whose bytes are not what its type says (a reader's reason, then inspect's
    sentence naming the container)."""


class TranscriptionError(ShadowHoundError):
    """Transcription failed; `status` is the HTTP status to answer the client with."""

    def __init__(self, message: str, status: int = 502) -> None:
        super().__init__(message)
        self.status = status


class HearingBusy(ShadowHoundError):
    """A recording not read or transcribed because others filled the lanes; `status` is the
    HTTP status to answer with (429: newer ones pushed it out; 503: it waited too long)."""

    def __init__(self, message: str, status: int) -> None:
        super().__init__(message)
        self.status = status
