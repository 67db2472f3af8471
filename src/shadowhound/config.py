"""Configuration: one typed model, loaded from a YAML profile, then environment, then options.

Precedence (lowest first): model defaults < profile file < environment variables
(`SHADOWHOUND_<SECTION>__<FIELD>`, e.g. `SHADOWHOUND_SAFETY__MAX_LINEAR_SPEED=0.3`) < explicit
overrides (CLI options, ROS parameters). Secrets (API keys) are read from the environment
variable a profile names and are never stored in the model.

Long because: it is the one typed model of every setting, a section per class, and its loader;
the robot backends' settings live apart (robot_config.py).
"""

from __future__ import annotations

import os
from collections.abc import Mapping
from pathlib import Path
from typing import Any, Literal

import yaml
from pydantic import BaseModel, ConfigDict, Field, ValidationError, field_validator, model_validator

from .errors import ConfigError
from .geofence import MAX_VERTICES, polygon_problem
from .robot_config import (
    ROBOT_TYPES,
    RobotSettings,
    SimRobotSettings,
)
from .state import not_finite

ENV_PREFIX = "SHADOWHOUND_"
_PACKAGE_DIR = Path(__file__).resolve().parent


def _finite_pair(value: Any) -> tuple[float, float]:
    """[x, y] in metres: two numbers, both finite (odometry-sized mistakes are refused here)."""
    if not isinstance(value, (list, tuple)) or len(value) != 2:
        raise ValueError(f"must be a pair [x, y] in metres, got {value!r:.40}")
    try:
        if any(isinstance(v, bool) for v in value):
            raise TypeError("a boolean is not a number")
        x, y = (float(v) for v in value)
    except (TypeError, ValueError):
        raise ValueError(
            f"must be a pair of numbers [x, y] in metres, got {list(value)!r:.40}"
        ) from None
    if bad := not_finite(x=x, y=y):
        raise ValueError(f"must be finite numbers, got {bad}")
    return (x, y)


class _Section(BaseModel):
    model_config = ConfigDict(extra="forbid", validate_assignment=True)


class SafetyConfig(_Section):
    """Limits every skill call must respect before it reaches the robot."""

    max_linear_speed: float = Field(0.5, gt=0, le=1.5, description="m/s cap on any translation")
    max_angular_speed: float = Field(1.0, gt=0, le=3.0, description="rad/s cap on any rotation")
    max_step_distance: float = Field(5.0, gt=0, le=100, description="metres one step may travel")
    geofence_radius: float = Field(
        10.0, gt=0, le=1000, description="metres around the odom origin the robot must stay in"
    )
    geofence_polygon: list[tuple[float, float]] | None = Field(
        None, description="optional polygon [[x, y], ...] in the odom frame the robot must stay in"
    )
    geofence_margin: float = Field(
        0.40,
        ge=0,
        le=10,
        description="metres the robot's centre keeps from every fence edge: "
        "its body (a Go2 is about 0.70 x 0.31 m, 0.38 m from centre to corner)",
    )
    max_linear_accel: float = Field(1.0, gt=0, le=10, description="m/s^2 cap on commands")
    max_angular_accel: float = Field(3.0, gt=0, le=20, description="rad/s^2 cap on commands")
    max_mission_distance: float = Field(
        50.0, gt=0, le=10_000, description="metres one mission may travel in all"
    )
    max_mission_duration: float = Field(
        600.0, gt=0, le=86_400, description="seconds on the robot's clock one mission may take"
    )
    battery_floor: float = Field(
        15.0, ge=0, le=100, description="percent below which only stop, sit, lie down, status"
    )
    allow_skills: list[str] | None = Field(
        None, description="only these skills (glob patterns such as 'body.*'); None = all"
    )
    deny_skills: list[str] = Field(default_factory=list, description="never these skills")
    allow_risky_tricks: bool = Field(
        False, description="run flips, jumps, pounce, handstand, bound without approval"
    )
    require_approval: bool = Field(False, description="every plan waits for approval")
    approval_timeout: float = Field(60.0, gt=0, le=3600, description="seconds to wait for it")
    max_wait: float = Field(300.0, gt=0, le=3600, description="longest sys.wait in seconds")
    watchdog_timeout: float = Field(
        0.25, gt=0, le=5, description="seconds without a control tick before zero velocity"
    )
    watchdog_grace: float = Field(
        2.0,
        gt=0,
        le=60,
        description="seconds a control loop the watchdog stopped the robot for may take to "
        "come back (it then goes on from rest) before the mission stops",
    )
    outcome_tolerance: float = Field(
        0.10, gt=0, le=5, description="metres a motion step may end away from its target"
    )
    outcome_tolerance_deg: float = Field(
        5.0, gt=0, le=180, description="degrees a motion step may end away from its heading"
    )
    step_travel_margin: float = Field(
        0.05,
        ge=0,
        le=1,
        description="metres a step may command beyond its planned leg, whatever odometry says",
    )
    step_travel_slack: float = Field(
        0.02,
        ge=0,
        le=0.5,
        description="fraction of a leg (or turn) a step may command beyond it, on top of "
        "step_travel_margin (step_turn_margin_deg)",
    )
    step_turn_margin_deg: float = Field(
        3.0, ge=0, le=45, description="degrees a step may command beyond its planned turn"
    )
    max_speech_chars: int = Field(
        200, ge=10, le=500, description="characters one saying keeps; longer text is cut"
    )
    max_speech_per_minute: int = Field(
        6, ge=0, le=60, description="sayings the robot speaks a minute (0 = never aloud)"
    )

    @field_validator("geofence_polygon", mode="before")
    @classmethod
    def _polygon(cls, value: Any) -> list[tuple[float, float]] | None:
        if value is None:
            return None
        if not isinstance(value, (list, tuple)) or not 3 <= len(value) <= MAX_VERTICES:
            raise ValueError(f"must be a list of 3 to {MAX_VERTICES} [x, y] vertices")
        points = [_finite_pair(v) for v in value]
        problem = polygon_problem(points)
        if problem:
            raise ValueError(f"is not a usable fence: {problem}")
        return points

    @model_validator(mode="after")
    def _margin_fits(self) -> SafetyConfig:
        if self.geofence_margin >= self.geofence_radius:
            raise ValueError(
                f"geofence_margin ({self.geofence_margin:g} m) must be smaller than "
                f"geofence_radius ({self.geofence_radius:g} m), or the robot could not move"
            )
        return self


class MotionConfig(_Section):
    """Closed-loop motion control shared by every robot."""

    control_rate_hz: float = Field(20.0, ge=1, le=200)
    default_linear_speed: float = Field(0.4, gt=0, le=1.5)
    default_angular_speed: float = Field(0.8, gt=0, le=3.0)
    linear_accel: float = Field(0.8, gt=0, le=5.0, description="m/s^2 used for ramps")
    angular_accel: float = Field(2.0, gt=0, le=10.0, description="rad/s^2 used for ramps")
    position_tolerance: float = Field(0.002, gt=0, le=0.5, description="metres")
    yaw_tolerance: float = Field(0.00002, gt=0, le=0.2, description="radians")
    stall_timeout: float = Field(3.0, gt=0, le=60, description="seconds without progress")
    auto_stand: bool = Field(True, description="stand up before moving when sitting or lying")


class SearchConfig(_Section):
    """Going to objects: how close to stand, and the budget for looking for one not seen yet."""

    standoff: float = Field(0.6, gt=0, le=5, description="metres from the object's surface")
    max_seconds: float = Field(
        120.0, gt=0, le=3600, description="robot-clock seconds a search may take"
    )
    max_distance: float = Field(20.0, gt=0, le=1000, description="metres a search may walk")
    view_range: float = Field(
        4.0, gt=0, le=20, description="metres within which a look counts a spot as seen"
    )


class SimConfig(_Section):
    """The simulated Go2."""

    time_scale: float = Field(
        0.0, ge=0, le=100, description="real seconds per simulated second; 0 = as fast as possible"
    )
    max_linear_speed: float = Field(1.0, gt=0, description="hardware limit, m/s")
    max_angular_speed: float = Field(2.0, gt=0, description="hardware limit, rad/s")
    linear_accel: float = Field(1.0, gt=0, description="m/s^2")
    angular_accel: float = Field(3.0, gt=0, description="rad/s^2")
    body_radius: float = Field(
        0.35, ge=0.05, le=2.0, description="metres: the body's collision circle in the scene"
    )
    collisions: bool = Field(
        True,
        description="the body stops at contact with the scene's objects and walls, and "
        "the robot is given the scene's map (off: a ghost that walks through them, no map)",
    )
    battery_drain_idle: float = Field(0.01, ge=0, description="percent per second standing")
    battery_drain_per_metre: float = Field(0.05, ge=0, description="percent per metre walked")
    camera_width: int = Field(160, ge=16, le=1920)
    camera_height: int = Field(120, ge=12, le=1080)
    command_log_size: int = Field(10000, ge=10, le=10_000_000)
    true_path_size: int = Field(
        100_000, ge=10, le=10_000_000, description="ground-truth path points kept (1 cm apart)"
    )


class LLMConfig(_Section):
    """Language-model backend (used when `backend` is not offline)."""

    model: str = Field("", description="model name as the server knows it")
    base_url: str = Field("", description="OpenAI-compatible endpoint, e.g. http://host:8000/v1")
    api_key_env: str = Field(
        "OPENAI_API_KEY", description="environment variable holding the API key ('' = none)"
    )
    timeout: float = Field(30.0, gt=0, le=600, description="seconds per request")
    max_retries: int = Field(2, ge=0, le=10, description="retries with exponential backoff")
    max_tokens: int = Field(512, ge=16, le=32768, description="completion tokens per request")
    temperature: float = Field(0.0, ge=0, le=2)
    mode: Literal["plan", "react"] = Field(
        "plan", description="plan: whole plan in one request; react: tool loop with observations"
    )
    plan_format: Literal["auto", "json_schema", "tools", "plain"] = Field(
        "auto",
        description="how plan mode asks for a plan: json_schema (the plan schema "
        "the server enforces), tools, or plain (JSON asked for in words); auto picks json_schema",
    )
    plan_schema: Literal["compact", "strict"] = Field(
        "compact",
        description="the plan schema sent with json_schema: compact (skill names and typed "
        "arguments, about a quarter of the size; the registry checks the rest) or strict (each "
        "skill with exactly its own arguments: helps a small local model, costs prompt time)",
    )
    hybrid: bool = Field(
        True, description="offline rules first; the model plans only what they do not understand"
    )
    repair_attempts: int = Field(1, ge=0, le=3, description="round trips to fix an invalid plan")
    max_reply_depth: int = Field(
        16, ge=4, le=200, description="how deep a reply's JSON may nest; deeper is refused"
    )
    react_max_steps: int = Field(8, ge=1, le=100, description="skill calls in one react mission")
    react_token_budget: int = Field(
        12000, ge=500, le=1_000_000, description="prompt + completion tokens for one mission"
    )
    check_on_start: bool = Field(True, description="check the server and model at start-up")
    vision: bool = Field(False, description="the model accepts images (perception.describe)")
    vision_max_side: int = Field(512, ge=64, le=2048, description="pixels; frames are downscaled")


class SpeechConfig(_Section):
    """Push-to-talk on the dashboard: recordings transcribed by an OpenAI-compatible server."""

    base_url: str = Field(
        "",
        description="OpenAI-compatible server with POST /audio/transcriptions, e.g. "
        "https://api.openai.com/v1 or a local speaches at http://127.0.0.1:8000/v1 ('' = off)",
    )
    model: str = Field("whisper-1", description="transcription model as the server knows it")
    language: str = Field("", description="ISO-639-1 language of the speech ('' = detected)")
    api_key_env: str = Field(
        "OPENAI_API_KEY", description="environment variable holding the API key ('' = none)"
    )
    timeout: float = Field(30.0, gt=0, le=300, description="seconds per transcription")
    confirm: bool = Field(False, description="show the transcript and ask before running it")
    speak_results: bool = Field(
        False,
        description="say each mission's result and chat answer on the robot's speaker (a Go2: "
        "its speech_topic, go2_ros2_sdk's /tts)",
    )
    max_seconds: float = Field(30.0, gt=0, le=300, description="longest recording taken")
    max_bytes: int = Field(
        2_000_000, ge=10_000, le=50_000_000, description="largest recording taken, bytes"
    )
    upload_timeout: float = Field(
        20.0,
        gt=0,
        le=300,
        description="seconds a recording may take to arrive (a client trickling it gets 408)",
    )


class MemoryConfig(_Section):
    """Mission history, taught places and retrieval memory."""

    enabled: bool = Field(False, description="keep history and taught places in data_dir")
    data_dir: str = Field("~/.shadowhound", description="where history.db and recall/ live")
    retention_days: float | None = Field(
        90.0, gt=0, description="delete missions older than this at start-up (None = keep)"
    )
    max_missions: int | None = Field(10000, ge=1, description="keep at most this many missions")
    enable_rag: bool = Field(False, description="retrieval memory (Chroma; 'memory' extra)")
    embedding: Literal["minilm", "backend"] = Field(
        "minilm", description="offline all-MiniLM-L6-v2, or the LLM server's /v1/embeddings"
    )
    embedding_model: str = Field("", description="model for embedding: backend")
    rag_top_k: int = Field(3, ge=1, le=20, description="memories given to planner and chat")
    rag_max_chars: int = Field(800, ge=100, le=20000, description="prompt space for memories")


class AgentConfig(_Section):
    """Behaviour of the mission loop."""

    max_mission_chars: int = Field(2000, ge=1, le=100_000)
    max_steps: int = Field(50, ge=1, le=1000)
    # What one plan may carry, whatever a model sends: checked before any step is read further,
    # so the work of checking a plan (and of each control tick) stays bounded.
    max_watches_per_step: int = Field(8, ge=1, le=100, description="conditions on one step")
    max_watches: int = Field(64, ge=1, le=1000, description="conditions in one plan")
    max_args_chars: int = Field(
        2000, ge=100, le=100_000, description="characters one step's arguments may carry"
    )
    conversation_history_size: int = Field(10, ge=0, le=1000)
    replan_on_failure: bool = True


class TeleopConfig(_Section):
    """Driving from the dashboard's pad (`shadowhound.teleop`)."""

    idle_timeout: float = Field(
        60.0,
        gt=0,
        le=3600,
        description="seconds with nobody driving (no deflection) before driving switches itself "
        "off, and missions are taken again",
    )


class ShadowHoundConfig(_Section):
    """Everything ShadowHound can be configured with. Loaded by `load_config`."""

    profile: str = "offline"
    backend: Literal["offline", "openai", "ollama", "vllm", "llamacpp"] = "offline"
    robot: RobotSettings = Field(
        default_factory=SimRobotSettings,
        description="the robot backend and its settings: 'sim', 'go2', or {type: go2, "
        "namespace: robot0, ...}",
    )
    navigation: Literal["auto", "nav2", "direct"] = Field(
        "auto",
        description="nav.goto: auto = the robot's Nav2 (navigate_to_pose) when it "
        "answers, else the project's own planner; nav2 = Nav2 required; direct = never Nav2",
    )
    safety: SafetyConfig = Field(default_factory=SafetyConfig)
    motion: MotionConfig = Field(default_factory=MotionConfig)
    search: SearchConfig = Field(default_factory=SearchConfig)
    sim: SimConfig = Field(default_factory=SimConfig)
    llm: LLMConfig = Field(default_factory=LLMConfig)
    agent: AgentConfig = Field(default_factory=AgentConfig)
    memory: MemoryConfig = Field(default_factory=MemoryConfig)
    speech: SpeechConfig = Field(default_factory=SpeechConfig)
    teleop: TeleopConfig = Field(default_factory=TeleopConfig)
    places: dict[str, tuple[float, float]] = Field(
        default_factory=lambda: {"kitchen": (4.0, 2.5), "charging dock": (-2.1, -1.0)},
        description="named places, metres, in the robot's world frame: SLAM's map on a Go2 with "
        "map -> odom on /tf, else odometry's frame",
    )
    patrol_route: list[tuple[float, float]] = Field(
        default_factory=lambda: [(2.0, 0.0), (2.0, 1.2), (0.0, 1.2)],
        description="waypoints visited by nav.patrol before it returns to where it started",
    )

    @field_validator("robot", mode="before")
    @classmethod
    def _robot(cls, value: Any) -> Any:
        """`robot: go2` is `robot: {type: go2}`."""
        if isinstance(value, str):
            if value not in ROBOT_TYPES:
                raise ValueError(f"must be one of {', '.join(ROBOT_TYPES)}, got {value!r}")
            return {"type": value}
        return value

    @model_validator(mode="after")
    def _robot_motion(self) -> ShadowHoundConfig:
        """A robot's motion settings default to its own (a Go2's: GO2_MOTION) where the profile
        and the environment leave them unset."""
        defaults = self.robot.motion_defaults
        if defaults:
            unset = {k: v for k, v in defaults.items() if k not in self.motion.model_fields_set}
            if unset:
                motion = self.motion.model_copy(update=unset)
                motion.model_fields_set.difference_update(unset)  # still the robot's defaults
                object.__setattr__(self, "motion", motion)
        return self

    @field_validator("places", mode="before")
    @classmethod
    def _places(cls, value: Any) -> dict[str, tuple[float, float]]:
        if not isinstance(value, Mapping):
            raise ValueError("must be a mapping of name -> [x, y]")
        return {str(k).strip().lower(): _finite_pair(v) for k, v in value.items()}

    @field_validator("patrol_route", mode="before")
    @classmethod
    def _route(cls, value: Any) -> list[tuple[float, float]]:
        if not isinstance(value, (list, tuple)) or not value:
            raise ValueError("must be a non-empty list of [x, y] waypoints")
        return [_finite_pair(v) for v in value]

    @model_validator(mode="after")
    def _speeds_within_hardware(self) -> ShadowHoundConfig:
        if self.motion.default_linear_speed > self.safety.max_linear_speed:
            self.motion.default_linear_speed = self.safety.max_linear_speed
        if self.motion.default_angular_speed > self.safety.max_angular_speed:
            self.motion.default_angular_speed = self.safety.max_angular_speed
        return self


def profiles_dirs() -> list[Path]:
    """Where named profiles live: inside the installed package, or the source tree's configs/."""
    return [_PACKAGE_DIR / "configs", _PACKAGE_DIR.parent.parent / "configs"]


def available_profiles() -> list[str]:
    names = {p.stem for d in profiles_dirs() if d.is_dir() for p in d.glob("*.yaml")}
    return sorted(names)


def _read_profile(profile: str) -> tuple[dict[str, Any], str]:
    path = Path(profile).expanduser()
    if profile.endswith((".yaml", ".yml")) or path.is_file():
        if not path.is_file():
            raise ConfigError(f"config file {str(path)!r} does not exist")
    else:
        candidates = [d / f"{profile}.yaml" for d in profiles_dirs()]
        found = next((c for c in candidates if c.is_file()), None)
        if found is None:
            raise ConfigError(
                f"unknown config profile {profile!r}; available profiles: "
                f"{', '.join(available_profiles()) or 'none'}, or give a path to a YAML file"
            )
        path = found
    try:
        data = yaml.safe_load(path.read_text(encoding="utf-8")) or {}
    except (OSError, UnicodeDecodeError, yaml.YAMLError) as exc:
        raise ConfigError(f"cannot read config {str(path)!r}: {exc}") from exc
    if not isinstance(data, dict):
        raise ConfigError(f"config {str(path)!r} must be a YAML mapping, not {type(data).__name__}")
    data.setdefault("profile", path.stem)
    return data, str(path)


def _env_overrides(environ: Mapping[str, str]) -> tuple[dict[str, Any], dict[str, str]]:
    """SHADOWHOUND_BACKEND=ollama, SHADOWHOUND_SAFETY__MAX_LINEAR_SPEED=0.3 ... as a nested dict,
    and which variable set each setting ("speech.api_key_env": "SHADOWHOUND_SPEECH__...").

    Values are parsed as YAML scalars so numbers and booleans keep their types; an empty value
    is the empty string, as `api_key_env: ""` is in a profile (no key, no server), not null.
    """
    out: dict[str, Any] = {}
    sources: dict[str, str] = {}
    for key, raw in environ.items():
        if not key.startswith(ENV_PREFIX) or key in ("SHADOWHOUND_CONFIG", "SHADOWHOUND_TOKEN"):
            continue
        path = key[len(ENV_PREFIX) :].lower().split("__")
        if path[0] not in ShadowHoundConfig.model_fields:
            continue
        try:
            value = yaml.safe_load(raw) if raw.strip() else ""
        except yaml.YAMLError:
            value = raw
        node = out
        for part in path[:-1]:
            node = node.setdefault(part, {})
        node[path[-1]] = value
        sources[".".join(path)] = key
    return out, sources


def _merge(base: dict[str, Any], extra: Mapping[str, Any]) -> dict[str, Any]:
    merged = dict(base)
    for key, value in extra.items():
        if isinstance(value, Mapping) and isinstance(merged.get(key), dict):
            merged[key] = _merge(merged[key], value)
        else:
            merged[key] = value
    return merged


def _layer(data: dict[str, Any], extra: Mapping[str, Any]) -> dict[str, Any]:
    """`extra` over `data`. A robot of another type replaces the robot settings whole: a
    Go2's namespace or a robot's name never carries over to another backend (its memories
    would be taken for the other robot's)."""
    robot = extra.get("robot")
    if isinstance(robot, Mapping):
        if "type" in robot and robot["type"] != _robot_type(data):
            data = {k: v for k, v in data.items() if k != "robot"}
        elif isinstance(data.get("robot"), str):  # `robot: go2` is `robot: {type: go2}`
            data = {**data, "robot": {"type": data["robot"]}}
    return _merge(data, extra)


def _robot_type(data: Mapping[str, Any]) -> Any:
    robot = data.get("robot", "sim")
    return robot.get("type", "sim") if isinstance(robot, Mapping) else robot


def _explain(exc: ValidationError, source: str, env: Mapping[str, str]) -> str:
    """Each problem with where it came from: the profile `source`, or the variable in `env`
    (setting -> variable) that set it."""
    problems, from_file = [], False
    for err in exc.errors():
        where = ".".join(str(p) for p in err["loc"]) or "(top level)"
        variable = next(
            (v for k, v in env.items() if where == k or where.startswith(k + ".")), None
        )
        said = f"{where}: {err['msg']} (got {err.get('input')!r})"
        problems.append(f"{said}, from the environment variable {variable}" if variable else said)
        from_file = from_file or variable is None
    origin = f"from {source}" if from_file else "from the environment"
    return f"invalid configuration {origin}: " + "; ".join(problems)


def load_config(
    profile: str | None = None,
    overrides: Mapping[str, Any] | None = None,
    environ: Mapping[str, str] | None = None,
) -> ShadowHoundConfig:
    """Build the configuration: profile (name or YAML path) < environment < overrides.

    `profile` defaults to $SHADOWHOUND_CONFIG, then to "offline". Raises ConfigError.
    """
    env = os.environ if environ is None else environ
    profile = profile or env.get("SHADOWHOUND_CONFIG") or "offline"
    data, source = _read_profile(profile)
    from_env, variables = _env_overrides(env)
    data = _layer(data, from_env)
    data = _layer(data, overrides or {})
    variables = {k: v for k, v in variables.items() if not _overridden(k, overrides or {})}
    try:
        return ShadowHoundConfig.model_validate(data)
    except ValidationError as exc:
        raise ConfigError(_explain(exc, source, variables)) from exc


def _overridden(setting: str, overrides: Mapping[str, Any]) -> bool:
    """Whether explicit overrides set `setting` ("speech.model"), over the environment."""
    node: Any = overrides
    for part in setting.split("."):
        if not isinstance(node, Mapping) or part not in node:
            return False
        node = node[part]
    return True
