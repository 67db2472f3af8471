"""bench/RESULTS.md is shared: each benchmark owns one section between its markers."""

from __future__ import annotations

from pathlib import Path

RESULTS = Path(__file__).with_name("RESULTS.md")


def write_section(name: str, section: str) -> None:
    """Replace the section `<!-- name:start --> ... <!-- name:end -->` (or append it).

    `section` must include both markers.
    """
    start, end = f"<!-- {name}:start -->", f"<!-- {name}:end -->"
    if not (section.startswith(start) and section.rstrip().endswith(end)):
        raise ValueError(f"the {name!r} section must start with {start} and end with {end}")
    text = RESULTS.read_text() if RESULTS.exists() else "# Benchmark results\n"
    if start in text:
        head, rest = text.split(start, 1)
        text = head + section.rstrip() + rest.split(end, 1)[1]
    else:
        text = text.rstrip() + "\n\n" + section.rstrip() + "\n"
    RESULTS.write_text(text)
