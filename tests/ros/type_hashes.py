"""Type hashes of ROS interface definitions, for the tests that pin the project's shipped copies
(nav2_msgs, vision_msgs, tf2_msgs, unitree_api, unitree_go) to the upstream packages': computed
from definition files with rosidl's own generators (scripts/type_hash.py), or read from an
installed package.
No rclpy import here."""

from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

from tests.ros.rosclient import ROOT

SCRIPT = ROOT / "scripts" / "type_hash.py"


def computed(package: str, *files: Path) -> dict[str, str]:
    """{type name: RIHS01 hash} of every type the definition `files` of `package` declare."""
    done = subprocess.run(
        [sys.executable, str(SCRIPT), package, *map(str, files)],
        capture_output=True,
        text=True,
        timeout=120,
        cwd="/tmp",
    )
    assert done.returncode == 0, done.stderr
    return dict(line.split() for line in done.stdout.splitlines())


def installed(module_file: str, package: str, kind: str, name: str) -> dict[str, str]:
    """{type name: hash} from an installed package's share/PACKAGE/KIND/NAME.json, where
    `module_file` is the package's Python `__file__` (PREFIX/lib/pythonX/site-packages/...)."""
    prefix = Path(module_file).resolve().parents[4]
    path = prefix / "share" / package / kind / f"{name}.json"
    entries = json.loads(path.read_text(encoding="utf-8"))["type_hashes"]
    return {h["type_name"]: h["hash_string"] for h in entries}
