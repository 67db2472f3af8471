"""Is the importable go2_interfaces go2_ros2_sdk's? Compares its WebRtcReq and Go2State, field
by field (names and types), with ros2/go2_interfaces/msg (which carries go2_ros2_sdk's exactly;
tests/ros/test_go2_interfaces.py holds that to upstream's type hashes).

    python scripts/check_go2_interfaces.py

Prints the package's directory, then exits 0 when every field matches, or 1 naming each field
that differs (on stderr); exits 2 when no go2_interfaces with those messages can be imported.
Used by scripts/build_ros.sh to decide whether a sourced workspace's package can be used.
"""

from __future__ import annotations

import importlib
import re
import sys
from pathlib import Path

MSG_DIR = Path(__file__).resolve().parents[1] / "ros2" / "go2_interfaces" / "msg"
MESSAGES = ("WebRtcReq", "Go2State")
# .msg primitive type -> the name rosidl's Python classes report
_PYTHON_NAMES = {"float32": "float", "float64": "double"}
_FIELD = re.compile(r"^([A-Za-z0-9_/]+)(\[\d*\])?\s+([A-Za-z_][A-Za-z0-9_]*)$")


def fields_of(msg_file: Path) -> dict[str, str]:
    """Field name -> type as rosidl's Python classes spell it, from a .msg file."""
    out = {}
    for line in msg_file.read_text(encoding="utf-8").splitlines():
        text = line.split("#", 1)[0].strip()
        if not text:
            continue
        match = _FIELD.match(" ".join(text.split()))
        if match is None:
            raise ValueError(f"{msg_file}: cannot read the line {line!r}")
        base, array, name = match.groups()
        out[name] = _PYTHON_NAMES.get(base, base) + (array or "")
    return out


def differences(name: str, theirs: dict[str, str], ours: dict[str, str]) -> list[str]:
    problems = [
        f"{name}.{f} is {theirs[f]}, go2_ros2_sdk's is {t}"
        for f, t in ours.items()
        if f in theirs and theirs[f] != t
    ]
    problems += [f"{name}.{f} is missing" for f in ours if f not in theirs]
    problems += [f"{name}.{f} is not in go2_ros2_sdk's" for f in theirs if f not in ours]
    if list(theirs) != list(ours) and not problems:
        problems.append(f"{name}'s fields are in another order than go2_ros2_sdk's")
    return problems


def main() -> int:
    try:
        package = importlib.import_module("go2_interfaces.msg")
        classes = [getattr(package, name) for name in MESSAGES]
    except (ImportError, AttributeError) as exc:
        print(f"no go2_interfaces with {' and '.join(MESSAGES)}: {exc}", file=sys.stderr)
        return 2
    where = Path(package.__file__).resolve().parents[1]
    problems = []
    for name, cls in zip(MESSAGES, classes, strict=True):
        problems += differences(
            name, dict(cls.get_fields_and_field_types()), fields_of(MSG_DIR / f"{name}.msg")
        )
    print(where)
    if problems:
        print(
            f"go2_interfaces at {where} is not go2_ros2_sdk's: " + "; ".join(problems),
            file=sys.stderr,
        )
        return 1
    return 0


if __name__ == "__main__":
    sys.exit(main())
