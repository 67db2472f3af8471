"""How far apart two words are, and how far a typo may go: one rule for every reader of names.

The offline planner reads misspelt words with it (planning/_spelling.py), and nav.goto matches a
misspelt place or object name with it (skills/objects.py), so both forgive the same typos.
"""

from __future__ import annotations


def distance(a: str, b: str, limit: int) -> int:
    """Edit distance with swaps of neighbours (optimal string alignment); > limit if far."""
    if abs(len(a) - len(b)) > limit:
        return limit + 1
    before: list[int] = []
    row = list(range(len(b) + 1))
    for i, ca in enumerate(a, start=1):
        current = [i] + [0] * len(b)
        for j, cb in enumerate(b, start=1):
            current[j] = min(row[j] + 1, current[j - 1] + 1, row[j - 1] + (ca != cb))
            if i > 1 and j > 1 and ca == b[j - 2] and a[i - 2] == cb:
                current[j] = min(current[j], before[j - 2] + 1)
        before, row = row, current
    return row[-1]


def limit(word: str) -> int:
    """How many edits a typo of `word` may make: one in a short word, two in a long one."""
    return 1 if len(word) <= 6 else 2
