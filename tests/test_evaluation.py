"""The planner must generalise: held-out sentences of the public kinds, never seen by the code."""

from pathlib import Path

import pytest

from shadowhound.config import ShadowHoundConfig
from shadowhound.evaluation import load_cases, run_case

DATA = Path(__file__).parent / "data"
HELD_OUT = load_cases(DATA / "missions_heldout.yaml")


@pytest.mark.parametrize("case", HELD_OUT, ids=[c.mission[:50] for c in HELD_OUT])
def test_held_out_case(case):
    outcome = run_case(case, ShadowHoundConfig())
    assert outcome.passed, f"{outcome.failures} -> {outcome.response}"
