"""How often the costly steps of setting up a run happen in this
process: Diagrams built and inverse-kinematics problems solved. What
``scripts/bench_plan.py`` and the tests read to hold a run to one build."""

from __future__ import annotations

from collections import Counter
from typing import Dict

__all__ = ["count", "counts", "reset_counts", "DIAGRAMS", "IK_SOLVES"]

#: The names counted.
DIAGRAMS = "diagrams_built"
IK_SOLVES = "ik_solves"

_COUNTS: Counter = Counter()


def count(name: str) -> None:
    """One more ``name``."""
    _COUNTS[name] += 1


def counts() -> Dict[str, int]:
    """{name: how many so far} of :data:`DIAGRAMS` and :data:`IK_SOLVES`."""
    return {name: _COUNTS[name] for name in (DIAGRAMS, IK_SOLVES)}


def reset_counts() -> None:
    _COUNTS.clear()
