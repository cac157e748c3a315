"""A run as one self-contained HTML page to explore in a browser, offline.

The page (``quadnav view DIR``, ``quadnav fly --html``) shows the map (blocks in their
colours, the boundary as a transparent box), the path in red, the trajectory coloured by
speed, the flown track (a Tello's: its dead-reckoned estimate, and its true track when the
run folder has one), start and goal, and the drone's body box that a time slider moves
along the flight; beside it, the metrics. The explored tree is drawn faint beneath the
lines, and off until its checkbox turns it on (on at first for a run without a path). It
draws with three.js (WebGL, a depth buffer, so near things hide far ones) and its orbit
controls: rotate by dragging, pan with shift or the right button, zoom with the wheel. No
network is needed: three.js (vendored from the npm registry's ``three`` 0.147.0, MIT, in
``viewer/three/`` with its licence), the viewer (``viewer/viewer.js``) and the run's
numbers (JSON) are written into the page (the template ``viewer.html`` of
:mod:`quadnav.pages`).
"""

from __future__ import annotations

import json
from importlib import resources
from pathlib import Path

import numpy as np
from markupsafe import Markup

from quadnav.files import atomic_output
from quadnav.pages import render
from quadnav.runs import Run, run_outcome
from quadnav.viz.thinning import evenly_spread

#: Tree edges written into the page at most; a larger tree is thinned to an evenly spread
#: subset, which keeps the page a few MB at most and drawing it interactive.
MAX_TREE_EDGES = 20_000
#: Decimals kept of positions (so 1 mm), speeds (1 mm/s) and times (1 ms).
DECIMALS = 3
#: Decimals kept of the attitude quaternions.
QUATERNION_DECIMALS = 4
_ASSETS = resources.files("quadnav.viz") / "viewer"
#: The vendored three.js scripts, in the order they define ``THREE`` and its add-ons.
THREE_SCRIPTS = ("three.min.js", "OrbitControls.js", "LineSegmentsGeometry.js",
                 "LineGeometry.js", "LineMaterial.js", "LineSegments2.js", "Line2.js")


def _numbers(values: np.ndarray, decimals: int = DECIMALS) -> list[float]:
    """``values`` rounded and flattened to a list (row after row), for JSON."""
    return np.round(np.asarray(values, dtype=float), decimals).ravel().tolist()


def _point(value: np.ndarray | None) -> list[float] | None:
    return None if value is None else _numbers(value)


def _subtitle(metrics: dict) -> str:
    """One line: the outcome (:func:`~quadnav.runs.run_outcome`, after ``FAILED:`` for a
    failure), then the planner, vehicle, top speed, path length and flight time that
    metrics.json gives (a missing one is left out)."""
    outcome = run_outcome(metrics)
    parts = [outcome if metrics.get("success") else f"FAILED: {outcome}"]
    for key, text in (("planner", "{}"), ("seed", "seed {}"), ("vehicle", "vehicle {}"),
                      ("speed_m_s", "top speed {:g} m/s"), ("path_length_m", "path {:.2f} m"),
                      ("flight_time_s", "flight {:.2f} s")):
        if metrics.get(key) is not None:
            parts.append(text.format(metrics[key]))
    return " \u00b7 ".join(parts)


def viewer_data(run: Run) -> dict:
    """The numbers the page draws, as JSON-ready lists (positions flattened x, y, z after
    x, y, z, in m; speeds in m/s; times in s). ``path``, ``trajectory`` and ``flight`` are
    None for a run that found no path; ``truth`` (the true track's positions) is None
    unless the run has one."""
    world, edges = run.world, run.tree_edges()
    vehicle = run.parameters.get("vehicle", {})
    arm = float(vehicle.get("arm_length", 0.0))
    data = {
        "title": run.title,
        "subtitle": _subtitle(run.metrics),
        "boundary": _numbers(world.boundary),
        "blocks": _numbers(world.blocks),
        "colors": _numbers(world.colors),
        "start": _point(world.start),
        "goal": _point(world.goal),
        "tree": _numbers(evenly_spread(edges, MAX_TREE_EDGES)),
        "treeEdges": len(edges),
        "path": _point(run.path),
        "trajectory": None,
        "flight": None,
        "truth": None if run.truth is None else _numbers(run.truth[:, 1:4]),
        "collision": bool(run.metrics.get("collision")),
        "armLength": arm,
        "bodySize": [float(v) for v in vehicle.get("body_size", (2 * arm, 2 * arm, arm / 2))],
        "metrics": run.metrics,
    }
    if run.trajectory is not None:
        data["trajectory"] = {
            "position": _numbers(run.trajectory.position),
            "speed": _numbers(np.linalg.norm(run.trajectory.velocity, axis=1)),
        }
    if run.flight is not None:
        data["flight"] = {
            "t": _numbers(run.flight.t),
            "position": _numbers(run.flight.position),
            "speed": _numbers(np.linalg.norm(run.flight.velocity, axis=1)),
            "attitude": _numbers(run.flight.attitude, QUATERNION_DECIMALS),
        }
    return data


def _script_json(value: dict) -> Markup:
    """``value`` as JSON that is safe inside a ``<script>`` element (no ``<`` at all, so no
    ``</script>`` can end it early), written into the page as it is."""
    return Markup(json.dumps(value, separators=(",", ":"), allow_nan=False)
                  .replace("<", "\\u003c"))


def viewer_html(run: Run) -> str:
    """The self-contained page of ``run``: the template with the renderer (the vendored
    scripts, trusted as they are) and the run's data written in (no external
    references)."""
    data = viewer_data(run)
    three_js = "\n;\n".join((_ASSETS / "three" / name).read_text(encoding="utf-8")
                            for name in THREE_SCRIPTS)
    return render("viewer.html", title=f"quadnav: {data['title']}",
                  three_js=Markup(three_js),
                  viewer_js=Markup((_ASSETS / "viewer.js").read_text(encoding="utf-8")),
                  run_data=_script_json(data))


def write_viewer(run: Run, path: str | Path) -> Path:
    """Write the page of ``run`` to ``path`` (whole or not at all); returns the path."""
    path = Path(path)
    page = viewer_html(run)
    with atomic_output(path) as tmp:
        tmp.write_text(page, encoding="utf-8")
    return path
