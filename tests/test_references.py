"""Built-in references: specs, exact derivatives, a smooth start and end; references read
back from the trajectory.csv and MP.csv files quadnav writes, and bad files."""

from __future__ import annotations

import re

import numpy as np
import pytest

from quadnav.errors import MapError, QuadnavError
from quadnav.trajectory.generate import TrajectorySettings, make_trajectory
from quadnav.trajectory.model import YawMode
from quadnav.trajectory.references.builtin import (
    ShapedReference,
    StepReference,
    build_reference,
    describe_references,
    load_reference,
    reference_names,
)
from quadnav.trajectory.references.contract import Reference, grid_times, sample_times, samples_at
from quadnav.trajectory.references.export import mp_csv, trajectory_csv
from quadnav.trajectory.references.sampled import COURSE_MP_RATE, MP_FORMAT, TABLE_FORMAT
from quadnav.trajectory.references.timelaw import PhaseLaw

DEFAULTS = {
    "hover": "hover:height=1,duration=5",
    "step": "step:axis=x,size=1,height=1,at=1,duration=6",
    "circle": "circle:radius=1,speed=1,laps=1,height=1,ramp=1",
    "helix": "helix:radius=1,speed=1,laps=2,climb=1,height=0.5,ramp=1",
    "figure8": "figure8:size=2,period=8,laps=1,height=1,ramp=1",
    "lissajous": "lissajous:ax=1,ay=1,az=0.3,fx=1,fy=2,fz=3,period=10,laps=1,height=1,ramp=1",
}
SHAPES = ["circle", "helix", "figure8", "lissajous", "helix:radius=0.5,speed=2,climb=-0.7,ramp=0.3",
          "lissajous:fx=3,fy=2,fz=0,period=4,laps=1.5,ramp=2"]


def test_every_builtin_is_named_by_its_canonical_spec_which_rebuilds_it():
    assert reference_names() == list(DEFAULTS)
    for name, canonical in DEFAULTS.items():
        reference = build_reference(name)
        assert isinstance(reference, Reference)
        assert reference.name == canonical
        assert build_reference(canonical).name == canonical
        assert np.array_equal(reference.position(0.0), build_reference(canonical).position(0.0))
    assert build_reference("helix: laps = 3 ,radius=2").name == (
        "helix:radius=2,speed=1,laps=3,climb=1,height=0.5,ramp=1")


def test_the_listing_gives_every_parameter_a_default_that_builds_and_a_range():
    infos = describe_references()
    assert [info.name for info in infos] == list(DEFAULTS)
    for info in infos:
        assert info.summary and all(p.help and p.range for p in info.params)
        spec = f"{info.name}:" + ",".join(f"{p.name}={p.default}" for p in info.params)
        assert build_reference(spec).name == DEFAULTS[info.name]
    step = {p.name: p for p in infos[1].params}
    assert step["axis"].type == "x|y|z" and step["axis"].range == "one of x, y, z"
    assert step["size"].range == "from -1,000 to 1,000 m"


@pytest.mark.parametrize(("spec", "fragment"), [
    ("spiral", "spiral: unknown built-in reference 'spiral' (known: hover, step, circle"),
    ("step:axis=w", "step:axis=w: axis: expected one of x, y, z, got 'w'"),
    ("step:size=0", "size: expected a step other than 0 m"),
    ("step:at=6", "at (6 s) must be before the end (duration 6 s)"),
    ("step:at=0", "at: expected above 0, at most 3,600 s, got 0"),
    ("circle:radius=0", "radius: expected from 0.01 to 1,000 m, got 0"),
    ("circle:speed=1e9", "speed: expected from 0.01 to 100 m/s"),
    ("helix:radius=1,radius=2", "parameter 'radius' given twice"),
    ("helix:spin=2", "unknown parameter 'spin' (valid: radius, speed, laps, climb, height, ramp)"),
    ("hover:", "empty parameter: expected key=value"),
    ("hover:height", "expected key=value, got 'height'"),
    ("lissajous:fx=1.5", "fx: expected an integer, got '1.5'"),
    ("figure8:laps=0.1,period=5", "0.1 laps take 0.5 s at the cruise rate, less than the ramp (1 s)"),
    ("circle:laps=1000,speed=0.01", "it lasts 628320 s, longer than the 3600 s a reference may last"),
    ("hover:duration=nan", "duration: expected a number, got 'nan'"),
])
def test_a_bad_spec_is_one_line_naming_it(spec, fragment):
    with pytest.raises(QuadnavError) as error:
        build_reference(spec)
    message = str(error.value)
    assert message.startswith(f"{spec}: ") and fragment in message and "\n" not in message


def _finite_differences(reference, t: np.ndarray, h: float = 1e-5):
    """Central differences of the position and the velocity at ``t``."""
    velocity = (reference.position(t + h) - reference.position(t - h)) / (2 * h)
    acceleration = (reference.velocity(t + h) - reference.velocity(t - h)) / (2 * h)
    return velocity, acceleration


@pytest.mark.parametrize("spec", SHAPES)
def test_velocity_and_acceleration_are_the_derivatives_of_the_position(spec):
    reference = build_reference(spec)
    assert isinstance(reference, ShapedReference)
    t = np.linspace(1e-3, reference.duration - 1e-3, 997)
    velocity, acceleration = _finite_differences(reference, t)
    scale_v = np.abs(reference.velocity(t)).max()
    scale_a = np.abs(reference.acceleration(t)).max()
    assert scale_v > 0.1 and scale_a > 0.1
    np.testing.assert_allclose(reference.velocity(t), velocity, atol=1e-6 * scale_v)
    np.testing.assert_allclose(reference.acceleration(t), acceleration, atol=1e-5 * scale_a)


@pytest.mark.parametrize("spec", SHAPES)
def test_a_shape_starts_and_ends_at_rest_and_is_smooth_across_the_ramps(spec):
    reference = build_reference(spec)
    ramp, end = reference.law.ramp, reference.duration
    for still in (-1.0, 0.0, end, end + 1.0):
        assert np.allclose(reference.velocity(still), 0, atol=1e-12)
        assert np.allclose(reference.acceleration(still), 0, atol=1e-12)
    assert np.allclose(reference.position(-1.0), reference.position(0.0))
    assert np.allclose(reference.position(end + 1.0), reference.position(end))
    assert np.allclose(reference.position(0.0)[:2], 0.0)
    # No jump of position, velocity or acceleration where a ramp begins or ends.
    for boundary in (0.0, ramp, end - ramp, end):
        before, after = np.array([boundary - 1e-9]), np.array([boundary + 1e-9])
        for state in (reference.position, reference.velocity, reference.acceleration):
            assert np.allclose(state(before), state(after), atol=1e-6)
    # The cruise speed is reached between the ramps.
    speed = np.linalg.norm(reference.velocity(np.linspace(ramp, end - ramp, 50)), axis=1)
    if spec == "circle":
        assert np.allclose(speed, 1.0)


def test_the_time_law_covers_its_phase_with_half_a_ramp_of_cruise_per_ramp():
    law = PhaseLaw(total=10.0, rate=2.0, ramp=1.5)
    assert law.duration == pytest.approx(10.0 / 2.0 + 1.5)
    phase, rate, change = law(np.array([0.0, 1.5, 3.0, law.duration - 1.5, law.duration]))
    assert np.allclose(phase, [0.0, 1.5, 4.5, 10.0 - 1.5, 10.0])
    assert np.allclose(rate, [0.0, 2.0, 2.0, 2.0, 0.0]) and np.allclose(change, 0.0)
    t = np.linspace(0.0, law.duration, 2001)
    phase, rate, _ = law(t)
    assert np.all(np.diff(phase) >= 0) and np.all(rate <= 2.0 + 1e-12)
    with pytest.raises(ValueError, match="ramps need"):
        PhaseLaw(total=1.0, rate=2.0, ramp=1.0)


def test_a_step_jumps_in_position_only_and_a_hover_holds_still():
    step = build_reference("step:axis=z,size=-0.5,height=2,at=1.5,duration=4")
    assert isinstance(step, StepReference) and step.is_step
    t = np.array([0.0, 1.4999, 1.5, 4.0, 9.0])
    assert np.array_equal(step.position(t)[:, 2], [2.0, 2.0, 1.5, 1.5, 1.5])
    assert np.array_equal(step.position(t)[:, :2], np.zeros((5, 2)))
    assert not np.any(step.velocity(t)) and not np.any(step.acceleration(t))
    assert step.position(1.0).shape == (3,) and np.shape(step.yaw(1.0)) == ()
    hover = build_reference("hover:height=0.7")
    assert not hover.is_step and hover.duration == 5
    assert np.array_equal(hover.position(np.linspace(0, 9, 10)), np.tile([0, 0, 0.7], (10, 1)))


def test_sample_times_end_at_the_end_and_grid_times_are_exactly_uniform():
    assert np.array_equal(sample_times(0.25, 0.1), [0.0, 0.1, 0.2, 0.25])
    assert sample_times(0.3, 0.1)[-1] == 0.3 and len(sample_times(0.3, 0.1)) == 4
    # An end a hair after a multiple of dt is not a sample of its own (it would print alike).
    assert np.array_equal(sample_times(0.2 + 1e-12, 0.1), [0.0, 0.1, 0.2 + 1e-12])
    grid = grid_times(0.25, 0.1)
    assert np.array_equal(grid, np.arange(4) * 0.1)
    assert np.array_equal(grid_times(0.3, 0.1), np.arange(4) * 0.1)


# ------------------------------------------------------------------------ files
def _written(tmp_path, reference, dt: float):
    """``reference`` written as trajectory.csv and MP.csv every ``dt`` s."""
    table, mp = tmp_path / "trajectory.csv", tmp_path / "MP.csv"
    table.write_text(trajectory_csv(reference, dt))
    mp.write_text(mp_csv(reference, dt))
    return table, mp


def _assert_equal_at(read: Reference, original: Reference, t: np.ndarray) -> None:
    """The two agree at ``t`` to the 9 significant digits written."""
    a, b = samples_at(read, t), samples_at(original, t)
    for mine, theirs in ((a.position, b.position), (a.velocity, b.velocity),
                         (a.acceleration, b.acceleration), (a.yaw, b.yaw)):
        scale = max(float(np.abs(theirs).max()), 1.0)
        np.testing.assert_allclose(mine, theirs, rtol=1e-8, atol=1e-9 * scale)


@pytest.mark.parametrize("dt", [0.01, 0.05])
def test_a_trajectory_reads_back_exactly_from_both_files(tmp_path, dt):
    path = np.array([[0.0, 0.0, 1.0], [2.0, 1.0, 1.5], [3.0, 3.0, 1.0], [0.5, 4.0, 2.0]])
    trajectory = make_trajectory(path, TrajectorySettings(yaw=YawMode.TRAVEL))
    table_file, mp_file = _written(tmp_path, trajectory, dt)
    table = load_reference(table_file)
    assert table.format == TABLE_FORMAT and table.name == str(table_file)
    assert table.duration == pytest.approx(trajectory.duration, rel=1e-9)
    _assert_equal_at(table, trajectory, table.samples.t)
    mp = load_reference(mp_file, rate=1 / dt)
    assert mp.format == MP_FORMAT
    assert mp.info == {"format": MP_FORMAT, "samples": len(mp.samples.t),
                       "sample_interval_s": dt, "rate_hz": 1 / dt}
    grid = np.arange(len(mp.samples.t)) * dt
    assert np.array_equal(mp.samples.t, grid) and grid[-2] < trajectory.duration <= grid[-1]
    # MP.csv has no yaw: 0, the trajectory's constant yaw.
    _assert_equal_at(mp, trajectory.replace(yaw_mode=YawMode.CONSTANT), grid)
    # Between the samples, the quintic Hermite interpolation stays close to the original.
    middle = grid[:-1] + dt / 2
    error = np.abs(mp.position(middle) - trajectory.position(middle)).max()
    assert error < (1e-4 if dt == 0.01 else 1e-2), error


def test_a_builtin_reference_reads_back_exactly_and_mp_csv_defaults_to_the_course_rate(tmp_path):
    helix = build_reference("helix:speed=1.5,ramp=0.5")
    table_file, _ = _written(tmp_path, helix, 0.01)
    _assert_equal_at(load_reference(table_file), helix, load_reference(table_file).samples.t)
    mp_file = tmp_path / "MP.csv"
    mp_file.write_text(mp_csv(helix, 1 / COURSE_MP_RATE))
    mp = load_reference(mp_file)
    assert mp.info["sample_interval_s"] == 0.05 and COURSE_MP_RATE == 20
    _assert_equal_at(mp, helix, mp.samples.t)


BAD_FILES = [
    ("1,2,3\n4,5,6\n", "MP.csv: expected 9 rows (x, y, z, vx, vy, vz, ax, ay, az: the course's MP.csv) or a trajectory.csv header, got 2 rows"),
    ("0,1\n" * 4 + "0,1,2\n" + "0,1\n" * 4, "MP.csv:5: 3 values, but line 1 has 2: expected one column per sample"),
    ("0,1\n" * 3 + "0,abc\n" + "0,1\n" * 5, "MP.csv:4: column 2: expected a number, got 'abc'"),
    ("0,1\n" * 8 + "0, inf\n", "MP.csv:9: column 2: expected a finite number, got 'inf'"),
    ("0\n" * 9, "MP.csv: expected at least 2 samples (columns), got 1"),
    ("0,1\n0,2e7\n" + "0,1\n" * 7, "MP.csv:2: column 2: y = 2e+07 m, expected from -10,000 to 10,000 m"),
    ("", "MP.csv: expected 9 rows"),
]


HEADER = "t,x,y,z,vx,vy,vz,ax,ay,az,yaw\n"
ROW = ",0,0,1,0,0,0,0,0,0,0\n"
BAD_TABLES = [
    ("time,x,y,z\n0,0,0,0\n", "trajectory.csv:1: expected the header 't,x,y,z,vx,vy,vz,ax,ay,az,yaw'"),
    (HEADER + "0" + ROW + "0.1,0,0\n", "trajectory.csv:3: expected 11 values (t,x,y,z"),
    (HEADER + "0" + ROW + "0.1" + ROW + "0.1" + ROW, "trajectory.csv:4: column 1: t = 0.1 s is not after the time before it (0.1 s)"),
    (HEADER + "0.5" + ROW + "1" + ROW, "trajectory.csv:2: column 1: the first time is 0.5 s, expected 0"),
    (HEADER + "0" + ROW, "trajectory.csv: expected at least 2 samples (rows), got 1"),
    (HEADER + "0" + ROW + "1,0,0,x" + ROW[6:], "trajectory.csv:3: column 4: expected a number, got 'x'"),
    (HEADER + "0" + ROW + "4000" + ROW, "trajectory.csv: the samples last 4000 s, longer than the 3600 s"),
]


@pytest.mark.parametrize(("text", "message"), BAD_FILES + BAD_TABLES)
def test_a_bad_file_is_one_line_naming_the_line_and_column(tmp_path, text, message):
    path = tmp_path / message.partition(":")[0]  # MP.csv or trajectory.csv
    path.write_text(text)
    with pytest.raises(MapError) as error:
        load_reference(path)
    assert str(error.value).startswith(str(tmp_path)) and message in str(error.value)
    assert "\n" not in str(error.value)


def test_an_unknown_source_and_a_bad_rate_are_one_line(tmp_path):
    with pytest.raises(QuadnavError, match=re.escape("nothing.csv: no such file, not a "
                                                     "built-in reference (built-in: hover")):
        load_reference(tmp_path / "nothing.csv")
    path = tmp_path / "MP.csv"
    path.write_text(mp_csv(build_reference("hover"), 0.05))
    with pytest.raises(QuadnavError, match=re.escape("MP.csv rate: expected from 0.1 to 100,000 Hz")):
        load_reference(path, rate=0.0)
