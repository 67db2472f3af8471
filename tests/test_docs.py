"""The documents say what the code does: every configuration field with its default, every
registered skill in the README's table, the package layout, the commands the architecture
names. Each test reads a document against the code, so a change to one without the other fails
here."""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any

import pytest
from pydantic import BaseModel

from shadowhound import ShadowHoundConfig
from shadowhound.cli import build_parser
from shadowhound.skills import default_registry

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = ROOT / "src" / "shadowhound"


def section(text: str, heading: str) -> str:
    """The text under a markdown heading, up to the next heading of the same or a higher level."""
    level = heading.split(" ")[0]
    start = text.index(heading + "\n")
    rest = text[start + len(heading) + 1 :]
    end = re.search(rf"^#{{1,{len(level)}}} ", rest, re.MULTILINE)
    return rest[: end.start()] if end else rest


def table_rows(text: str) -> list[list[str]]:
    """The cells of every markdown table row, header and rule rows left out."""
    rows = []
    for line in text.splitlines():
        if not line.startswith("|") or re.fullmatch(r"\|[-| :]+\|", line.strip()):
            continue
        rows.append([c.strip() for c in line.strip().strip("|").split("|")])
    return rows


# -- docs/configuration.md ---------------------------------------------------------------------


def documented_fields() -> dict[tuple[str, str], str]:
    """(section, field) -> the default cell, from docs/configuration.md's table (a row with an
    empty section cell belongs to the section above; one row may name several fields)."""
    text = (ROOT / "docs" / "configuration.md").read_text(encoding="utf-8")
    found: dict[tuple[str, str], str] = {}
    current = None
    for cells in table_rows(text):
        if cells[:2] == ["section", "field"]:
            current = ""
            continue
        if current is None or len(cells) < 3:
            continue
        if cells[0]:
            current = cells[0].strip("`")
        names = re.findall(r"`([a-z_0-9]+)`", cells[1])
        defaults = [d.strip() for d in cells[2].split(",")] if len(names) > 1 else [cells[2]]
        for i, name in enumerate(names):
            found[(current, name)] = defaults[i] if len(defaults) == len(names) else cells[2]
    return found


def model_fields() -> dict[tuple[str, str], Any]:
    """(section, field) -> default, for every field of ShadowHoundConfig ('' for the top)."""
    config = ShadowHoundConfig()
    out: dict[tuple[str, str], Any] = {}
    for name in ShadowHoundConfig.model_fields:
        value = getattr(config, name)
        if isinstance(value, BaseModel):
            for field in type(value).model_fields:
                out[(name, field)] = getattr(value, field)
        else:
            out[("", name)] = value
    return out


def test_configuration_doc_names_every_field_of_every_section() -> None:
    documented, fields = documented_fields(), model_fields()
    missing = sorted(set(fields) - set(documented))
    unknown = sorted(set(documented) - set(fields))
    assert not missing, f"docs/configuration.md lacks {missing}"
    assert not unknown, f"docs/configuration.md names fields the model has not: {unknown}"


def _agrees(cell: str, value: Any) -> bool:
    """Whether a default cell says `value` (numbers may carry a unit: "0.002 m", "90 days")."""
    cell = cell.strip("` ")
    if value is None:
        return cell.lower().startswith(("none", "null", "all", "off"))
    if isinstance(value, bool):
        return cell.lower() == str(value).lower()
    if isinstance(value, (int, float)):
        number = re.match(r"-?[0-9][0-9_]*(\.[0-9]+)?(e-?[0-9]+)?", cell)
        return number is not None and float(number.group().replace("_", "")) == value
    if isinstance(value, str):
        return cell == value or (value == "" and cell in ("''", '""', "(empty)"))
    return True  # places, routes, lists: said in words


@pytest.mark.parametrize("key", sorted(model_fields()), ids=lambda k: ".".join(filter(None, k)))
def test_configuration_doc_gives_each_default(key: tuple[str, str]) -> None:
    cell = documented_fields().get(key)
    if cell is None:
        pytest.skip("not documented (the test above fails)")
    value = model_fields()[key]
    assert _agrees(cell, value), f"{'.'.join(filter(None, key))}: doc says {cell!r}, is {value!r}"


# -- README.md ---------------------------------------------------------------------------------


def readme() -> str:
    return (ROOT / "README.md").read_text(encoding="utf-8")


def test_readme_skills_table_lists_every_registered_skill() -> None:
    rows = table_rows(section(readme(), "## Skills"))
    listed = {name for cells in rows for name in re.findall(r"`([a-z_]+\.[a-z_]+)`", cells[0])}
    assert listed == set(default_registry().names)


def test_readme_layout_names_every_part_of_the_package_and_nothing_else() -> None:
    layout = section(readme(), "## Layout")
    rooms = {p.name for p in PACKAGE.iterdir() if (p / "__init__.py").is_file()}
    named = set(re.findall(r"`([a-z_0-9]+)/`", layout))
    assert rooms <= named, f"README's Layout lacks {sorted(rooms - named)}"
    for name in named:
        assert (PACKAGE / name).is_dir() or (ROOT / name).is_dir(), f"no {name}/"
    for module in re.findall(r"`([a-z_0-9]+\.py)`", layout):
        assert (PACKAGE / module).is_file(), f"README's Layout names {module}: there is none"


# -- docs/architecture.md ----------------------------------------------------------------------


def test_architecture_names_only_commands_that_exist() -> None:
    text = (ROOT / "docs" / "architecture.md").read_text(encoding="utf-8")
    line = re.search(r"`shadowhound ([a-z|-]+)\|\.\.\.`", text)
    assert line, "docs/architecture.md no longer lists the commands as `shadowhound a|b|...`"
    parser = build_parser()
    commands = next(a for a in parser._actions if a.dest == "command").choices
    for name in line.group(1).split("|"):
        assert name in commands, f"docs/architecture.md names `shadowhound {name}`: no such command"


# -- docs/go2-stack.md -------------------------------------------------------------------------


def go2_stack() -> str:
    return (ROOT / "docs" / "go2-stack.md").read_text(encoding="utf-8")


def test_go2_stack_doc_gives_each_node_parameter_with_its_default() -> None:
    """The table of what ShadowHound reads and writes: each parameter exists, and a default
    given as `name` (`value` ...) is the node's."""
    from shadowhound.ros.params import PARAMETERS

    rows = table_rows(section(go2_stack(), "## What ShadowHound reads and writes on each"))
    cells = [row[-1] for row in rows[1:]]
    named = [n for cell in cells for n in re.findall(r"`([a-z0-9_]+)`(?= \(|,|$)", cell)]
    assert {"odom_topic", "coco_detections_topic", "speech_topic", "map_topic"} <= set(named)
    for name in named:
        assert name in PARAMETERS, f"docs/go2-stack.md names parameter {name}: there is none"
    for cell in cells:
        for name, value in re.findall(r"`([a-z0-9_]+)` \(`([^`]*)`", cell):
            default = PARAMETERS[name][0]
            assert ("" if value == "''" else value) == str(default), (name, value, default)


def test_go2_stack_doc_uses_only_options_and_parameters_that_exist() -> None:
    """Every `--option` of a `shadowhound` command in its code blocks and of the doctor in its
    text, and every `-p name:=value` given to the node."""
    from shadowhound.ros.params import PARAMETERS

    text = go2_stack()
    parser = build_parser()
    commands = next(a for a in parser._actions if a.dest == "command").choices

    def options(command: str) -> set[str]:
        if command == "sim-driver":  # its options are its own parser's (ROS owns the rest)
            from shadowhound.sim_driver.options import build_parser as driver_parser

            return {s for a in driver_parser("", "", "")._actions for s in a.option_strings}
        return {s for a in commands[command]._actions for s in a.option_strings}

    blocks = re.findall(r"```bash\n(.*?)```", text, re.DOTALL)
    runs = re.findall(r"shadowhound ([a-z-]+)((?:[^\n]|\\\n)*)", "\n".join(blocks))
    assert {"doctor", "node", "sim-driver"} <= {command for command, _ in runs}
    for command, args in runs:
        assert command in commands, f"docs/go2-stack.md runs `shadowhound {command}`"
        for name in re.findall(r"-p ([a-z0-9_]+):=", args):
            assert name in PARAMETERS, f"docs/go2-stack.md sets node parameter {name}"
        if command == "node":
            continue
        for option in re.findall(r"(?<![\w-])(--[a-z][a-z0-9-]*)", args):
            assert option in options(command), f"`shadowhound {command} {option}`: no such option"
    doctor = section(text, "## Checking each part: `shadowhound doctor --go2`")
    for option in re.findall(r"`(--[a-z][a-z0-9-]*)", doctor):
        assert option in options("doctor"), f"`shadowhound doctor {option}`: no such option"
