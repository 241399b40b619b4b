"""The repository's scenes, shipped inside the package so that examples run from any folder.

>>> import rpod
>>> sim = rpod.Simulation(rpod.scenes.path("orbit_approach_latch"), record=False)
>>> rpod.scenes.names()[:3]
['collision_course', 'docking_aligned', 'docking_miss']

In a source checkout the files here are links to the scene files under ``scenes/examples/`` and
``scenes/papers/PAPER/`` (one copy of each scene); a wheel holds the files themselves.
"""

from __future__ import annotations

import os
from typing import List

_HERE = os.path.dirname(os.path.abspath(__file__))


def names() -> List[str]:
    """Names of the bundled scenes (file names without ``.ron``), sorted."""
    return sorted(f[:-4] for f in os.listdir(_HERE) if f.endswith(".ron"))


def path(name: str) -> str:
    """The file of the bundled scene ``name`` (with or without ``.ron``); a KeyError lists the
    names when there is no such scene (a name is never taken as a path: ``../x`` is refused)."""
    if not isinstance(name, str):
        raise TypeError(f"a scene name is a str, got {type(name).__name__}")
    stem = name[:-4] if name.endswith(".ron") else name
    if stem not in names():
        raise KeyError(f"no bundled scene {name!r}; the scenes are: {', '.join(names())}")
    return os.path.join(_HERE, stem + ".ron")


__all__ = ["names", "path"]
