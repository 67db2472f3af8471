"""Print the ROS 2 type hashes (RIHS01) of a .msg, .srv or .action definition, computed with
rosidl's own generators (rosidl_adapter, rosidl_generator_type_description; both come with
scripts/build_ros.sh), exactly as a build of the package would compute them.

    python scripts/type_hash.py PACKAGE FILE [FILE ...]

e.g. `python scripts/type_hash.py nav2_msgs NavigateToPose.action` with Nav2 Jazzy's own file
(ros-navigation/navigation2, branch jazzy, nav2_msgs/action/NavigateToPose.action) gives the
hashes tests/ros/test_nav2_msgs.py holds ours to. Prints one `type_name hash` line per type
(the action, its goal/result/feedback, services and feedback message). Types it refers to
(geometry_msgs ...) are read from the installed packages' type descriptions (AMENT_PREFIX_PATH,
else this interpreter's prefix).
"""

from __future__ import annotations

import contextlib
import io
import json
import os
import shutil
import sys
import tempfile
from pathlib import Path

_KINDS = {".msg": "msg", ".srv": "srv", ".action": "action"}


def _share_dirs() -> dict[str, Path]:
    prefixes = [p for p in os.environ.get("AMENT_PREFIX_PATH", "").split(os.pathsep) if p]
    prefixes.append(sys.prefix)
    out: dict[str, Path] = {}
    for prefix in prefixes:
        share = Path(prefix, "share")
        if share.is_dir():
            for pkg in share.iterdir():
                out.setdefault(pkg.name, pkg)
    return out


def type_hashes(package: str, files: list[Path]) -> dict[str, str]:
    """Type name -> RIHS01 hash of every type the definitions in `files` make."""
    from rosidl_adapter.action import convert_action_to_idl
    from rosidl_adapter.msg import convert_msg_to_idl
    from rosidl_adapter.srv import convert_srv_to_idl
    from rosidl_generator_type_description import generate_type_hash

    convert = {
        "msg": convert_msg_to_idl,
        "srv": convert_srv_to_idl,
        "action": convert_action_to_idl,
    }
    with tempfile.TemporaryDirectory() as tmp:
        src, idl, out = Path(tmp, "src"), Path(tmp, "idl"), Path(tmp, "out")
        tuples = []
        for file in files:
            kind = _KINDS.get(file.suffix)
            if kind is None:
                raise ValueError(f"{file}: not a .msg, .srv or .action file")
            (src / kind).mkdir(parents=True, exist_ok=True)
            shutil.copy(file, src / kind / file.name)
            with contextlib.redirect_stdout(io.StringIO()):  # it prints each file it reads
                convert[kind](src, package, Path(kind, file.name), idl / kind)
            tuples.append(f"{idl}:{kind}/{file.stem}.idl")
        args = Path(tmp, "args.json")
        args.write_text(
            json.dumps(
                {
                    "package_name": package,
                    "output_dir": str(out),
                    "idl_tuples": tuples,
                    "include_paths": [
                        f"{name}:{path}" for name, path in _share_dirs().items() if name != package
                    ],
                }
            )
        )
        hashes: dict[str, str] = {}
        for path in generate_type_hash(str(args)):
            for entry in json.loads(Path(path).read_text())["type_hashes"]:
                if entry["type_name"].startswith(package + "/"):
                    hashes[entry["type_name"]] = entry["hash_string"]
        return dict(sorted(hashes.items()))


def main(argv: list[str]) -> int:
    if len(argv) < 2:
        print(__doc__, file=sys.stderr)
        return 2
    for name, value in type_hashes(argv[0], [Path(f) for f in argv[1:]]).items():
        print(name, value)
    return 0


if __name__ == "__main__":
    sys.exit(main(sys.argv[1:]))
