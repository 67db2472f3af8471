"""`strict_loads`: JSON read as RFC 8259 and a browser's JSON.parse read it (no NaN, no
Infinity), for tests of what the project sends out."""

from __future__ import annotations

import json


def strict_loads(text: str | bytes) -> object:
    """The value of `text`; raises ValueError on the literals NaN, Infinity and -Infinity,
    which Python's json accepts and no strict reader does."""

    def refuse(literal: str) -> object:
        raise ValueError(f"not JSON: {literal}")

    return json.loads(text, parse_constant=refuse)
