"""The map of the house holds: the rooms of docs/architecture.md, read from the source.

Each module of `src/shadowhound` lives in a room; rooms stand on levels, and a module imports
only from its own room or from a room on a lower level (never up, never sideways into a sibling
room). Module-level imports have no cycles. Only the worker starts a mission that moves the
robot. A module over 400 lines says at its top why it is one concept (a docstring line
starting "Long because:"), or is split.

The imports are read with `ast`, not by importing: a module that is only ever imported lazily
(rclpy, FastAPI) is checked like any other.
"""

from __future__ import annotations

import ast
from dataclasses import dataclass
from pathlib import Path

import pytest

SRC = Path(__file__).resolve().parents[1] / "src"
PACKAGE = SRC / "shadowhound"

# Rooms from the bottom up (the map in docs/architecture.md). A room imports its own modules
# and rooms on lower levels; rooms on one level are siblings that do not import each other.
# A subpackage is a room of its own name (a new one must be given a level here); top-level
# modules not named in BASE are core (the agent, its mission pipeline and what it shares).
LEVELS: tuple[tuple[str, ...], ...] = (
    ("base",),  # plain data and rules every room shares: state, plan, units, config, events ...
    # the model client (HTTP, no skills); the belief (grid, planner, objects); transcription
    ("llm", "world", "hearing"),
    ("memory", "robot"),  # history, places, recall; the Robot protocol, simulator, Go2 driver
    ("skills",),  # typed skills over the Robot protocol, reading the belief
    ("planning",),  # text -> Plan: offline rules, the model planner's prompts, parsing, schema
    ("core",),  # RobotAgent, the safety governor, plan checking, chat, the worker, evaluation
    ("web", "ros", "mcp"),  # the humble interfaces, over the public API
    ("sim_driver",),  # `shadowhound sim-driver`: a simulated driver built on the simulator
    ("cli",),  # the `shadowhound` command: an interface itself, and it starts the others
)
BASE = {
    "approval",
    "budget",
    "camera",
    "config",
    "errors",
    "events",
    "geofence",
    "jsonout",
    "plan",
    "result",
    "robot_config",
    "speech",
    "state",
    "typos",
    "units",
    "usage",
    "watchdog",
}

# Known exceptions, each with why and who removes it. Keep this list short.
KNOWN_CYCLES: set[frozenset[str]] = set()  # cycles through TYPE_CHECKING imports: none
KNOWN_CROSSINGS: dict[tuple[str, str], str] = {
    # By design: the ROS node serves the dashboard on its own mission worker (enable_web_ui).
    ("shadowhound.ros.node", "shadowhound.web.app"): "hosts the dashboard",
    ("shadowhound.ros.node", "shadowhound.web.server"): "hosts the dashboard",
}


def module_name(path: Path) -> str:
    parts = list(path.relative_to(SRC).with_suffix("").parts)
    return ".".join(parts[:-1] if parts[-1] == "__init__" else parts)


MODULES = {module_name(p): p for p in sorted(PACKAGE.rglob("*.py"))}


def room_of(module: str) -> str:
    parts = module.split(".")
    if len(parts) == 1:
        return "core"  # the package's public API (__init__) is the agent's facade
    if parts[1] == "__main__":
        return "cli"
    if (PACKAGE / parts[1]).is_dir():
        return parts[1]  # a package not in LEVELS fails test_every_module_is_in_a_room
    return "base" if parts[1] in BASE else "core"


LEVEL_OF = {room: level for level, rooms in enumerate(LEVELS) for room in rooms}


@dataclass(frozen=True)
class Import:
    source: str
    target: str
    line: int
    module_level: bool  # at the module's top level (not inside a function)
    type_only: bool  # under `if TYPE_CHECKING:`: read by type checkers, never run


def _is_type_checking(test: ast.expr) -> bool:
    return (isinstance(test, ast.Name) and test.id == "TYPE_CHECKING") or (
        isinstance(test, ast.Attribute) and test.attr == "TYPE_CHECKING"
    )


def _targets(node: ast.Import | ast.ImportFrom, module: str, is_package: bool) -> list[str]:
    """The shadowhound modules an import statement loads (`from . import x` loads `x`)."""
    if isinstance(node, ast.Import):
        return [a.name for a in node.names if a.name.split(".")[0] == "shadowhound"]
    if node.level:
        base = module.split(".") if is_package else module.split(".")[:-1]
        base = base[: len(base) - node.level + 1]
        target = ".".join(base + ([node.module] if node.module else []))
    else:
        target = node.module or ""
    if target.split(".")[0] != "shadowhound":
        return []
    found = [f"{target}.{a.name}" for a in node.names if f"{target}.{a.name}" in MODULES]
    return found or [target]


def imports_of(module: str) -> list[Import]:
    path = MODULES[module]
    found: list[Import] = []

    def visit(node: ast.AST, module_level: bool, type_only: bool) -> None:
        if isinstance(node, (ast.Import, ast.ImportFrom)):
            found.extend(
                Import(module, t, node.lineno, module_level, type_only)
                for t in _targets(node, module, path.name == "__init__.py")
            )
            return
        if isinstance(node, ast.If) and _is_type_checking(node.test):
            for child in node.body:
                visit(child, module_level, True)
            for child in node.orelse:
                visit(child, module_level, type_only)
            return
        inner = module_level and not isinstance(
            node, (ast.FunctionDef, ast.AsyncFunctionDef, ast.Lambda)
        )
        for child in ast.iter_child_nodes(node):
            visit(child, inner, type_only)

    visit(ast.parse(path.read_text(encoding="utf-8")), True, False)
    return found


IMPORTS = [i for m in MODULES for i in imports_of(m)]


def test_every_module_is_in_a_room() -> None:
    rooms = {room_of(m) for m in MODULES}
    assert rooms <= set(LEVEL_OF), f"rooms without a level: {sorted(rooms - set(LEVEL_OF))}"


def test_imports_point_down_the_rooms() -> None:
    """Lazy and TYPE_CHECKING imports count too: they still lean on the room they name."""
    wrong = []
    for imp in IMPORTS:
        source, target = room_of(imp.source), room_of(imp.target)
        if source == target or (imp.source, imp.target) in KNOWN_CROSSINGS:
            continue
        if LEVEL_OF[target] >= LEVEL_OF[source]:
            wrong.append(
                f"{imp.source} ({source}) imports {imp.target} ({target}), line {imp.line}"
            )
    assert not wrong, "imports that point up or sideways:\n" + "\n".join(wrong)


def _cycles(edges: dict[str, set[str]]) -> list[list[str]]:
    """Strongly connected components with more than one module (Tarjan's algorithm)."""
    index: dict[str, int] = {}
    low: dict[str, int] = {}
    stack: list[str] = []
    on_stack: set[str] = set()
    found: list[list[str]] = []

    def connect(node: str) -> None:
        index[node] = low[node] = len(index)
        stack.append(node)
        on_stack.add(node)
        for nxt in sorted(edges.get(node, ())):
            if nxt not in index:
                connect(nxt)
                low[node] = min(low[node], low[nxt])
            elif nxt in on_stack:
                low[node] = min(low[node], index[nxt])
        if low[node] == index[node]:
            component = []
            while True:
                member = stack.pop()
                on_stack.discard(member)
                component.append(member)
                if member == node:
                    break
            if len(component) > 1:
                found.append(sorted(component))

    for node in sorted(edges):
        if node not in index:
            connect(node)
    return found


def module_edges(*, with_types: bool = False) -> dict[str, set[str]]:
    """Module-level imports between modules (`with_types`: TYPE_CHECKING ones too). Importing
    `a.b` also runs package `a`'s __init__, but that is not an edge: a package may import its
    own submodules."""
    edges: dict[str, set[str]] = {m: set() for m in MODULES}
    for imp in IMPORTS:
        if (
            imp.module_level
            and (with_types or not imp.type_only)
            and imp.target in MODULES
            and imp.target != imp.source
        ):
            edges[imp.source].add(imp.target)
    return edges


def test_no_import_cycles() -> None:
    cycles = _cycles(module_edges())
    assert not cycles, "modules that import each other (module level): " + "; ".join(
        " <-> ".join(c) for c in cycles
    )


def test_no_cycles_even_in_the_types() -> None:
    """A cycle that only TYPE_CHECKING hides is still two modules that need each other."""
    found = _cycles(module_edges(with_types=True))
    cycles = [c for c in found if frozenset(c) not in KNOWN_CYCLES]
    assert not cycles, "modules that import each other (with TYPE_CHECKING): " + "; ".join(
        " <-> ".join(c) for c in cycles
    )
    gone = KNOWN_CYCLES - {frozenset(c) for c in found}
    assert not gone, f"cycles no longer there: remove them from KNOWN_CYCLES: {gone}"


def test_known_crossings_are_still_there() -> None:
    pairs = {(imp.source, imp.target) for imp in IMPORTS}
    gone = sorted(set(KNOWN_CROSSINGS) - pairs)
    assert not gone, f"crossings no longer there: remove them from KNOWN_CROSSINGS: {gone}"


def test_the_checks_catch_what_they_forbid() -> None:
    """The graph reader sees the imports this test is about (so a silent reader cannot pass)."""
    edges = module_edges()
    assert "shadowhound.camera" in edges["shadowhound.robot.go2.robot"]
    assert "shadowhound.planning.prompts" in edges["shadowhound.planning.llm"]
    assert "shadowhound.llm.backend" in edges["shadowhound.planning.llm"]
    assert _cycles({"a": {"b"}, "b": {"c"}, "c": {"a"}, "d": {"a"}}) == [["a", "b", "c"]]
    assert room_of("shadowhound.robot.go2.robot") == "robot"
    assert LEVEL_OF["robot"] < LEVEL_OF["ros"] and LEVEL_OF["llm"] < LEVEL_OF["skills"]
    assert LEVEL_OF["llm"] < LEVEL_OF["planning"] and LEVEL_OF["world"] < LEVEL_OF["robot"]


# What of robot/go2/ is not go2_ros2_sdk's: the sport API table, late-pose tracking, posture.
GO2_SHARED = {
    "shadowhound.robot.go2.api",
    "shadowhound.robot.go2.motion",
    "shadowhound.robot.go2.odometry",
    "shadowhound.robot.go2.posture",
    "shadowhound.robot.go2.stamps",
}


def test_the_go2_edu_backend_is_a_room_of_the_robot_and_reuses_only_go2s_shared_parts() -> None:
    """robot/go2_edu/ (the Go2 EDU over unitree_ros2) is a backend folder in the robot room; of
    robot/go2/ it imports only what is not go2_ros2_sdk's (imported, never copied), and no
    other backend imports it: the factory is the one place its name becomes a robot."""
    edu = [m for m in MODULES if m.startswith("shadowhound.robot.go2_edu")]
    assert "shadowhound.robot.go2_edu.robot" in edu
    assert {room_of(m) for m in edu} == {"robot"}
    edges = module_edges()
    used = {t for m in edu for t in edges.get(m, set()) if t.startswith("shadowhound.robot.go2.")}
    assert used and used <= GO2_SHARED, used - GO2_SHARED
    importers = {
        m
        for m, targets in edges.items()
        for t in targets
        if t.startswith("shadowhound.robot.go2_edu")
    }
    assert importers - set(edu) <= {"shadowhound.robot.factory"}, importers


def test_interfaces_run_missions_only_through_the_worker() -> None:
    """One mission at a time, for every interface: only worker.py starts a mission that moves
    the robot (a dry run moves nothing, so an interface may ask for one directly)."""
    interfaces = [m for m in MODULES if room_of(m) in LEVELS[-2] + LEVELS[-1]]
    starts = []
    for module in interfaces:
        for node in ast.walk(ast.parse(MODULES[module].read_text(encoding="utf-8"))):
            if (
                isinstance(node, ast.Call)
                and isinstance(node.func, ast.Attribute)
                and node.func.attr in ("execute_mission", "run_plan")
            ):
                starts.append(f"{module}, line {node.lineno}: {node.func.attr}")
    assert "shadowhound.cli.missions" in interfaces
    assert not starts, "missions started outside the worker:\n" + "\n".join(starts)


def test_interfaces_stop_and_cancel_only_through_the_worker() -> None:
    """The e-stop sequence and the cancel of a job are the worker's (`estop`, `cancel`): no
    interface drops the queue or flags a job cancelled itself."""
    interfaces = [m for m in MODULES if room_of(m) in LEVELS[-2] + LEVELS[-1]]
    rebuilt = []
    for module in interfaces:
        for node in ast.walk(ast.parse(MODULES[module].read_text(encoding="utf-8"))):
            if not (isinstance(node, ast.Call) and isinstance(node.func, ast.Attribute)):
                continue
            target = node.func.value
            if node.func.attr == "drop_queued" or (
                node.func.attr == "set"
                and isinstance(target, ast.Attribute)
                and target.attr == "cancelled"
            ):
                rebuilt.append(f"{module}, line {node.lineno}: {ast.unparse(node.func)}")
    assert not rebuilt, "stop or cancel rebuilt outside the worker:\n" + "\n".join(rebuilt)


# -- module size -------------------------------------------------------------------------

MAX_LINES = 400
SIZE_EXEMPT: set[str] = set()  # none: a long module says why at its top


@pytest.mark.parametrize("module", sorted(MODULES))
def test_a_long_module_says_why_at_its_top(module: str) -> None:
    text = MODULES[module].read_text(encoding="utf-8")
    lines = text.count("\n")
    if module in SIZE_EXEMPT:
        assert lines > MAX_LINES, f"{module} is short now: remove it from SIZE_EXEMPT"
        return
    if lines <= MAX_LINES:
        return
    doc = ast.get_docstring(ast.parse(text)) or ""
    reasons = [line for line in doc.splitlines() if line.startswith("Long because:")]
    assert reasons, (
        f"{module} has {lines} lines (over {MAX_LINES}): split it along a seam, "
        "or say why it is one concept in a module docstring line starting "
        "'Long because:'"
    )
