"""quadnav is free to use: its licence is in the metadata pip shows, and every work of others
that the package carries is named in THIRD_PARTY_NOTICES.md with its source."""

from __future__ import annotations

import importlib.metadata
from pathlib import Path

import quadnav

ROOT = Path(__file__).resolve().parents[1]
PACKAGE = Path(quadnav.__file__).parent


def test_the_installed_metadata_gives_the_mit_licence_and_carries_its_text():
    distribution = importlib.metadata.distribution("quadnav")
    assert distribution.metadata["License-Expression"] == "MIT"
    shipped = {Path(str(file)).name for file in distribution.files or ()
               if "licenses" in Path(str(file)).parts}
    assert {"LICENSE", "THIRD_PARTY_NOTICES.md"} <= shipped
    assert (ROOT / "LICENSE").read_text().startswith("MIT License")


def test_every_course_gain_table_and_vendored_library_is_in_the_notices():
    notices = (ROOT / "THIRD_PARTY_NOTICES.md").read_text()
    tables = sorted(PACKAGE.glob("control/course/*.toml"))
    assert tables  # the course teams' gain tables ship with the package
    for table in tables:
        assert f"`control/course/{table.name}`" in notices, table.name
        assert "as published in" in table.read_text() or "Recovered from" in table.read_text()
    assert (PACKAGE / "viz/viewer/three/LICENSE").read_text().startswith("The MIT License")
    assert "three.js" in notices and "src/quadnav/viz/viewer/three/" in notices
    rotorpy = PACKAGE / "world/coursemaps/rotorpy"
    assert "Copyright 2023 RotorPy Authors" in (rotorpy / "LICENSE.md").read_text()
    for world in sorted(rotorpy.glob("*.json")):
        assert world.name in notices, world.name
