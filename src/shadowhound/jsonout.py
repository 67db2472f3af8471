"""Strict JSON out (RFC 8259): the one way ShadowHound writes JSON for anyone else to read.

Python's `json` writes a float that is not finite as the literal `NaN`, `Infinity` or
`-Infinity`, which strict readers refuse: a browser's `JSON.parse`, `jq`, most ROS tools. One
such number from odometry that lies would make a whole message unreadable (the dashboard's
live feed froze on it). So every edge that sends or stores JSON (the web feed and API, the
security gates' answers, the ROS String topics, the CLI's `--json`, MCP tool results, the
history's JSON columns) writes it with `dumps` or `dump` here: a number that is not finite
becomes `null` ("not known"), and the encoder refuses anything else that is not JSON.

`number` is the same rule for a single value, for `to_dict()`s that round what they carry.
Standard library only.
"""

from __future__ import annotations

import json
import math
from collections.abc import Callable
from typing import IO, Any

__all__ = ["dump", "dumps", "finite", "number"]


def number(value: float, digits: int | None = None) -> float | None:
    """`value` rounded to `digits` (None: as it is), or None when it is not a finite number."""
    if not math.isfinite(value):
        return None
    return value if digits is None else round(value, digits)


def finite(value: Any) -> Any:
    """`value` with every float that is not finite replaced by None, through dicts, lists and
    tuples (a tuple becomes a list, as JSON has it; a dict key that is such a float becomes
    None, written "null"). Anything else is returned as it is. Raises ValueError on a
    container that holds itself (JSON cannot write it)."""
    return _finite(value, set())


def _finite(value: Any, seen: set[int]) -> Any:
    if isinstance(value, float):
        return value if math.isfinite(value) else None
    if isinstance(value, (dict, list, tuple)):
        if id(value) in seen:
            raise ValueError("Circular reference detected")
        seen.add(id(value))
        try:
            if isinstance(value, dict):
                return {_finite(k, seen): _finite(v, seen) for k, v in value.items()}
            return [_finite(v, seen) for v in value]
        finally:
            seen.discard(id(value))
    return value


def dumps(value: Any, *, default: Callable[[Any], Any] | None = None, **options: Any) -> str:
    """JSON text of `value`, strict: numbers that are not finite are written as null.

    `default` and `options` are `json.dumps`'s (`allow_nan` is always False); what `default`
    returns is made finite too. Raises TypeError or ValueError as `json.dumps` does for what
    is not JSON.
    """
    try:  # the common case, every number finite: the C encoder alone, no walk
        return json.dumps(value, allow_nan=False, default=default, **options)
    except ValueError:
        pass  # a number that is not finite somewhere (a cycle is reported again below)
    made = None if default is None else _finite_default(default)
    return json.dumps(finite(value), allow_nan=False, default=made, **options)


def dump(
    value: Any, fp: IO[str], *, default: Callable[[Any], Any] | None = None, **options: Any
) -> None:
    """`dumps` into a text file."""
    fp.write(dumps(value, default=default, **options))


def _finite_default(default: Callable[[Any], Any]) -> Callable[[Any], Any]:
    def made(obj: Any) -> Any:
        return finite(default(obj))

    return made
