"""Differential-drive kinodynamic RRT: exact arcs, free tree edges, replayable controls."""

from __future__ import annotations

import numpy as np
import pytest

from quadnav.errors import MapError, QuadnavError
from quadnav.kinodynamic import KinoSettings
from quadnav.kinodynamic.diffdrive import (
    CHORD_TOLERANCE,
    DiffDrive,
    control_profile,
    plan_diffdrive,
    propagate,
    track,
    wheel_tracks,
)
from quadnav.kinodynamic.world2d import load_world2d, read_map2d, slice_world
from quadnav.world import load_world

MODEL = DiffDrive()
SETTINGS = KinoSettings(max_iterations=20000, time_limit=60)


def rk4_unicycle(state, control, duration, steps=20000):
    """The unicycle ODE x' = v cos(theta), y' = v sin(theta), theta' = omega by RK4."""
    v, omega = control

    def f(s):
        return np.array([v * np.cos(s[2]), v * np.sin(s[2]), omega])

    s, h = np.array(state, dtype=float), duration / steps
    for _ in range(steps):
        k1 = f(s)
        k2 = f(s + h / 2 * k1)
        k3 = f(s + h / 2 * k2)
        k4 = f(s + h * k3)
        s = s + h / 6 * (k1 + 2 * k2 + 2 * k3 + k4)
    return s


@pytest.mark.parametrize("control", [(0.8, 1.2), (-0.2, -0.7), (1.0, 1e-9), (0.5, 0.0)])
def test_exact_integration_matches_rk4(control):
    start = np.array([1.0, -2.0, 0.3])
    exact = propagate(start, control, 2.0)
    reference = rk4_unicycle(start, control, 2.0)
    assert np.allclose(exact[:2], reference[:2], atol=1e-9)
    assert np.angle(np.exp(1j * (exact[2] - reference[2]))) == pytest.approx(0.0, abs=1e-9)


def test_straight_line_and_full_circle():
    assert np.allclose(propagate([0.0, 0.0, 0.0], [1.0, 0.0], 2.5), [2.5, 0.0, 0.0])
    circle = propagate([1.0, 2.0, 0.5], [0.6, 1.2], 2 * np.pi / 1.2)
    assert np.allclose(circle, [1.0, 2.0, 0.5], atol=1e-12)


def test_track_chords_stay_within_the_tolerance_of_the_arc():
    samples = track([0.0, 0.0, 0.0], [1.0, 1.5], 2.0, CHORD_TOLERANCE)
    fine = track([0.0, 0.0, 0.0], [1.0, 1.5], 2.0, 1e-7)
    radius = 1.0 / 1.5  # the arc's centre is (0, radius)
    mid = 0.5 * (samples[:-1, :2] + samples[1:, :2])
    sagitta = radius - np.linalg.norm(mid - [0.0, radius], axis=1)
    assert sagitta.max() <= CHORD_TOLERANCE and len(fine) > len(samples)


def plan_forest(seed: int, biased: bool = True, iterations: int = 20000):
    world2d = slice_world(load_world("forest"), 1.0)
    settings = SETTINGS.replace(seed=seed, biased=biased, max_iterations=iterations)
    return world2d, plan_diffdrive(world2d, [1.0, 1.0, np.pi / 4], [19.0, 19.0], settings)


def test_every_tree_edge_is_free_along_its_exact_motion_and_controls_replay():
    world2d, result = plan_forest(seed=3)
    assert result.solved and result.planner == "diffdrive"
    assert np.linalg.norm(result.states[-1, :2] - [19.0, 19.0]) <= SETTINGS.goal_radius
    footprint = world2d.inflate(MODEL.radius)
    for child in range(1, len(result.tree_states)):
        parent = result.tree_parents[child]
        motion = track(result.tree_states[parent], result.tree_controls[child],
                       result.tree_durations[child], 1e-3)
        assert np.allclose(motion[-1], result.tree_states[child], atol=1e-9)
        assert footprint.points_free(motion[:, :2]).all()
    replayed = [result.states[0]]
    for control, duration in zip(result.controls, result.durations, strict=True):
        replayed.append(propagate(replayed[-1], control, duration))
    assert np.allclose(replayed, result.states, atol=1e-9)
    assert np.all(np.abs(result.controls[:, 1]) <= MODEL.omega_max)
    assert np.all((result.controls[:, 0] >= MODEL.v_min) & (result.controls[:, 0] <= MODEL.v_max))


def test_wheel_tracks_and_wheel_speeds():
    _, result = plan_forest(seed=1)
    centre, left, right, t = wheel_tracks(result, MODEL)
    assert np.allclose(np.linalg.norm(left - right, axis=1), MODEL.wheel_base)
    assert np.allclose(0.5 * (left + right), centre)
    assert t[0] == 0.0 and t[-1] == pytest.approx(result.duration)
    times, v, omega, left_speed, right_speed = control_profile(result, MODEL)
    assert times[0] == 0.0 and np.all(np.diff(times) >= 0)
    assert np.allclose(0.5 * (left_speed + right_speed), v)
    assert np.allclose((right_speed - left_speed) / MODEL.wheel_base, omega)


def test_same_seed_same_plan():
    _, first = plan_forest(seed=5)
    _, again = plan_forest(seed=5)
    assert np.array_equal(first.states, again.states)
    assert np.array_equal(first.controls, again.controls)


def test_biased_sampling_reaches_the_goal_in_fewer_iterations():
    seeds = range(6)
    biased = [plan_forest(seed, True, 3000)[1] for seed in seeds]
    unbiased = [plan_forest(seed, False, 3000)[1] for seed in seeds]
    counts = ([r.iterations for r in biased], [r.iterations for r in unbiased])
    print(f"iterations to the goal, biased {counts[0]}, unbiased {counts[1]} (cap 3000)")
    assert all(r.solved for r in biased)
    assert np.median(counts[0]) < np.median(counts[1])


def test_course_map_slice_and_a_map2d_file(shared_maps, tmp_path):
    world2d = load_world2d(shared_maps / "rbe595" / "map1.txt", 4.0)
    result = plan_diffdrive(world2d, [1.0, -4.0, np.pi / 2], [8.0, 18.0], SETTINGS)
    assert result.solved
    path = tmp_path / "room.map2d"
    path.write_text("# a room with a wall\nboundary 0 0 10 6\nrect 4 0 5 4.5\n")
    room = read_map2d(path)
    assert len(room) == 1
    result = plan_diffdrive(room, [1.0, 1.0, 0.0], [8.0, 1.0], SETTINGS)
    assert result.solved and result.states[:, 1].max() > 4.5  # around the wall's end


def test_bad_maps_and_queries_are_user_errors(tmp_path):
    path = tmp_path / "bad.map2d"
    path.write_text("boundary 0 0 10 6\nrect 4 0 five 4.5\n")
    with pytest.raises(MapError, match=r"bad.map2d:2"):
        read_map2d(path)
    room = load_world2d(load_world("window"), 1.0)
    wall = room.rects[0]
    inside = [(wall[0] + wall[2]) / 2, (wall[1] + wall[3]) / 2, 0.0]
    with pytest.raises(QuadnavError, match="rect 0"):
        plan_diffdrive(room, inside, [5.0, 19.0], SETTINGS)
    with pytest.raises(QuadnavError):
        slice_world(load_world("forest"), 99.0)
