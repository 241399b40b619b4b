"""Shared paths: the repository's scenes (the tests run from any folder)."""

import os
import pathlib

import pytest

REPO = pathlib.Path(__file__).resolve().parents[2]
SCENES = REPO / "scenes"
EXAMPLES = SCENES / "examples"
FLAGSHIP = EXAMPLES / "orbit_approach_latch.ron"


@pytest.fixture
def out_dir(tmp_path):
    return tmp_path / "out"


def scene(name: str) -> str:
    return os.fspath(EXAMPLES / name)
