"""One error tree (shadowhound.errors) and one set of exit codes (shadowhound.exit_codes).

These read the source as it is, so a new exception class or exit code defined somewhere else,
or a caller that tells errors apart by their class name, fails here with where it is.
"""

from __future__ import annotations

import ast
import builtins
import importlib
import inspect
from pathlib import Path

import pytest

from shadowhound import errors
from shadowhound.exit_codes import ExitCode

SRC = Path(errors.__file__).resolve().parent
BUILTIN_EXCEPTIONS = {
    name
    for name, value in vars(builtins).items()
    if inspect.isclass(value) and issubclass(value, BaseException)
}
TREE = {
    name
    for name, value in vars(errors).items()
    if inspect.isclass(value)
    and issubclass(value, BaseException)
    and value.__module__ == errors.__name__
}


def _modules() -> list[tuple[Path, ast.Module]]:
    return [
        (path, ast.parse(path.read_text(encoding="utf-8"), str(path)))
        for path in sorted(SRC.rglob("*.py"))
    ]


def _base_name(node: ast.expr) -> str:
    if isinstance(node, ast.Name):
        return node.id
    if isinstance(node, ast.Attribute):
        return node.attr
    return ""


def test_every_exception_class_is_defined_in_errors() -> None:
    elsewhere = []
    for path, tree in _modules():
        if path.name == "errors.py" and path.parent == SRC:
            continue
        for node in ast.walk(tree):
            if isinstance(node, ast.ClassDef):
                bases = {_base_name(b) for b in node.bases}
                if bases & (BUILTIN_EXCEPTIONS | TREE):
                    elsewhere.append(f"{path.relative_to(SRC)}:{node.lineno} {node.name}")
    assert not elsewhere, f"exception classes outside shadowhound/errors.py: {elsewhere}"


def test_every_class_of_the_tree_derives_from_the_root_and_is_exported() -> None:
    assert sorted(TREE) == sorted(errors.__all__)
    for name in TREE:
        cls = getattr(errors, name)
        assert issubclass(cls, errors.ShadowHoundError), name
        assert cls.__doc__, f"{name} needs a docstring saying what it means"


@pytest.mark.parametrize(
    "module, name",
    [
        ("shadowhound", "ShadowHoundError"),
        ("shadowhound", "ConfigError"),
        ("shadowhound", "PlanningError"),
        ("shadowhound", "RobotError"),
        ("shadowhound", "SkillValidationError"),
        ("shadowhound.config", "ConfigError"),
        ("shadowhound.plan", "PlanningError"),
        ("shadowhound.robot.base", "RobotError"),
        ("shadowhound.skills", "SkillValidationError"),
        ("shadowhound.skills.context", "SkillError"),
        ("shadowhound.skills.context", "SkillTimeout"),
        ("shadowhound.skills.context", "PlanProblem"),
        ("shadowhound.skills.context", "MissionCancelled"),
        ("shadowhound.llm", "BackendError"),
        ("shadowhound.llm", "BackendUnavailable"),
        ("shadowhound.llm.backend", "BackendCancelled"),
        ("shadowhound.units", "UnitError"),
        ("shadowhound.world", "PlanError"),
        ("shadowhound.world.grid", "GridError"),
        ("shadowhound.memory", "MemoryStoreError"),
        ("shadowhound.memory", "RecallStoreError"),
        ("shadowhound.evaluation", "CaseFileError"),
        ("shadowhound.planning._errors", "NotUnderstood"),
        ("shadowhound.cli", "UsageError"),
        ("shadowhound.ros.params", "ParameterError"),
        ("shadowhound.serving", "ServeError"),
        ("shadowhound.web.frames", "FrameUnavailable"),
        ("shadowhound.mcp.desk", "ToolInputError"),
    ],
)
def test_old_import_paths_give_the_one_class(module: str, name: str) -> None:
    if module.startswith(("shadowhound.web", "shadowhound.mcp", "shadowhound.ros")):
        pytest.importorskip({"web": "fastapi", "mcp": "mcp", "ros": "rclpy"}[module.split(".")[1]])
    assert getattr(importlib.import_module(module), name) is getattr(errors, name)


@pytest.mark.parametrize(
    "name",
    [
        "SkillValidationError",
        "PlanProblem",
        "GridError",
        "UnitError",
        "CaseFileError",
        "ToolInputError",
    ],
)
def test_value_errors_stay_value_errors(name: str) -> None:
    # pydantic turns a ValueError raised in a validator into a field error; callers catch them
    assert issubclass(getattr(errors, name), ValueError)


def test_an_unreachable_backend_is_a_configuration_and_a_backend_error() -> None:
    exc = errors.BackendUnavailable("cannot reach http://127.0.0.1:9/v1")
    assert isinstance(exc, errors.ConfigError) and isinstance(exc, errors.BackendError)
    assert exc.status is None and str(exc) == "cannot reach http://127.0.0.1:9/v1"


def test_planning_errors_carry_their_usage() -> None:
    from shadowhound.plan import Usage

    assert errors.PlanningError("no").usage == Usage()
    spent = Usage(prompt_tokens=3, completion_tokens=4, round_trips=1)
    assert errors.PlanningError("no", usage=spent).usage is spent


def test_nothing_tells_errors_apart_by_class_name() -> None:
    """`type(exc).__name__ == "X"` breaks silently on a rename or a subclass: catch by class."""
    found = []
    for path, tree in _modules():
        for node in ast.walk(tree):
            if not isinstance(node, ast.Compare):
                continue
            for side in (node.left, *node.comparators):
                if isinstance(side, ast.Attribute) and side.attr in ("__name__", "__qualname__"):
                    found.append(f"{path.relative_to(SRC)}:{node.lineno}")
    assert not found, f"class-name comparisons: {found}"


# -- exit codes ------------------------------------------------------------------------------

_COMMANDS = ("main", "serve", "serve_main", "run_node")


def test_exit_codes_are_defined_once() -> None:
    assert [int(c) for c in ExitCode] == [0, 1, 2, 130, 141]
    elsewhere = []
    for path, tree in _modules():
        if path.name == "exit_codes.py":
            continue
        for node in ast.walk(tree):
            targets: list[ast.expr] = []
            if isinstance(node, ast.Assign):
                targets = node.targets
            elif isinstance(node, ast.AnnAssign):
                targets = [node.target]
            names = [n.id for t in targets for n in ast.walk(t) if isinstance(n, ast.Name)]
            elsewhere += [
                f"{path.relative_to(SRC)}:{node.lineno} {n}" for n in names if n.startswith("EXIT_")
            ]
    assert not elsewhere, f"exit codes defined outside shadowhound/exit_codes.py: {elsewhere}"


def test_commands_return_named_exit_codes_not_numbers() -> None:
    numbers = []
    for path, tree in _modules():
        for func in ast.walk(tree):
            if not isinstance(func, (ast.FunctionDef, ast.AsyncFunctionDef)):
                continue
            if func.name not in _COMMANDS and not func.name.startswith("cmd_"):
                continue
            for node in ast.walk(func):
                value = node.value if isinstance(node, ast.Return) else None
                if isinstance(node, ast.Call) and _base_name(node.func) in ("exit", "SystemExit"):
                    value = node.args[0] if node.args else None
                if isinstance(value, ast.Constant) and isinstance(value.value, int):
                    numbers.append(f"{path.relative_to(SRC)}:{node.lineno} {value.value}")
    assert not numbers, f"exit codes as bare numbers: {numbers}"


def test_exit_codes_print_as_numbers() -> None:
    assert f"{ExitCode.USAGE}" == str(ExitCode.USAGE) == "2"
