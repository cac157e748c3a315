"""``quadnav animate``: a GIF (and an MP4 where ffmpeg is installed) of a real run."""

from __future__ import annotations

import contextlib
import io
import shutil
import subprocess

import numpy as np
import pytest
from clitools import assert_user_error, run_here
from matplotlib.colors import to_rgb
from PIL import Image

from quadnav.cli.main import main
from quadnav.mission import MissionSettings, fly_mission
from quadnav.planning import PlannerSettings
from quadnav.report.run_writer import write_run
from quadnav.runs import read_run
from quadnav.viz.animation import DRONE_COLOR, frame_times, gif_rate, save_animation
from quadnav.world import load_world

SMALL = "forest:size=12x12x4,seed=2"


def write_mission(folder, iterations: int | None = None):
    """Fly the small forest (``iterations`` samples of search: None for the default) and
    write its run folder without figures; returns the folder."""
    settings = MissionSettings(planning=PlannerSettings(seed=0, max_iterations=iterations))
    write_run(fly_mission(load_world(SMALL), settings=settings), folder, figures=False)
    return folder


@pytest.fixture(scope="module")
def flown(tmp_path_factory):
    return write_mission(tmp_path_factory.mktemp("run"))


@pytest.fixture(scope="module")
def pathless(tmp_path_factory):
    return write_mission(tmp_path_factory.mktemp("pathless"), iterations=1)


def quadnav(*args) -> subprocess.CompletedProcess:
    """``quadnav ARGS`` run in this process (the real CLI, without a process's start-up)."""
    out, err = io.StringIO(), io.StringIO()
    with contextlib.redirect_stdout(out), contextlib.redirect_stderr(err):
        try:
            code = main([str(arg) for arg in args])
        except SystemExit as stop:
            code = stop.code
    return subprocess.CompletedProcess(args, code, out.getvalue(), err.getvalue())


def near(frame: Image.Image, color: str, tolerance: float = 40.0) -> np.ndarray:
    """Mask of the pixels of ``frame`` within ``tolerance`` of a matplotlib colour."""
    rgb = np.asarray(frame.convert("RGB"), dtype=float)
    return np.linalg.norm(rgb - 255 * np.array(to_rgb(color)), axis=2) < tolerance


def test_a_gif_of_the_flight(flown, tmp_path):
    gif = tmp_path / "flight.gif"
    result = run_here("animate", flown, "-o", gif, "--max-frames", "40", "--quiet")
    assert result.returncode == 0, result.stderr
    assert "40 frames of 800 x 600 pixels at 20 fps" in result.stdout
    assert "faster than --speed 1" in result.stdout  # a 16 s flight in 40 frames
    with Image.open(gif) as image:
        assert image.format == "GIF" and image.size == (800, 600)
        assert image.n_frames == 40 and image.info["loop"] == 0
        frames = []
        for k in range(image.n_frames):
            image.seek(k)
            assert image.info["duration"] == 50
            frames.append(image.convert("RGB"))
    drone = [near(frame, DRONE_COLOR) for frame in frames]
    assert all(mask.sum() > 20 for mask in drone)  # the drone is in every frame
    centres = np.array([np.argwhere(mask).mean(axis=0) for mask in drone])
    assert np.linalg.norm(centres[-1] - centres[0]) > 200  # and flies across the map
    # The flown track grows: more black pixels at the end than at the start.
    assert near(frames[-1], "black").sum() > near(frames[0], "black").sum() + 500


def test_speed_and_frame_rate_set_the_frames(flown, tmp_path):
    gif = tmp_path / "fast.gif"
    info = save_animation(read_run(flown), gif, fps=10.0, speed=8.0, max_frames=150)
    duration = read_run(flown).flight.t[-1]
    intervals = int(np.ceil(duration * 10 / 8))
    assert info.frames == intervals + 1 and info.fps == 10.0
    assert info.speed == pytest.approx(duration * 10 / intervals)
    with Image.open(gif) as image:
        assert image.n_frames == info.frames and image.info["duration"] == 100


def test_frame_times_cover_the_flight_and_are_bounded():
    times, speed = frame_times(16.0, 20.0, 1.0, 150)
    assert len(times) == 150 and times[0] == 0.0 and times[-1] == 16.0
    assert speed == pytest.approx(16.0 * 20.0 / 149)
    times, speed = frame_times(16.0, 20.0, 4.0, 150)
    assert len(times) == 81 and speed == pytest.approx(4.0)
    assert np.allclose(np.diff(times), 0.2)
    assert len(frame_times(0.0, 20.0, 1.0, 150)[0]) == 2
    assert gif_rate(15.0) == pytest.approx(100 / 7) and gif_rate(50.0) == 50.0


@pytest.mark.skipif(shutil.which("ffmpeg") is None, reason="ffmpeg is not installed")
def test_an_mp4_of_the_flight(flown, tmp_path):
    mp4 = tmp_path / "flight.mp4"
    result = quadnav("animate", flown, "-o", mp4, "--max-frames", "20", "--quiet")
    assert result.returncode == 0, result.stderr
    data = mp4.read_bytes()
    assert data[4:8] == b"ftyp" and len(data) > 10_000


def test_an_mp4_without_ffmpeg_is_a_user_error(flown, tmp_path, monkeypatch):
    monkeypatch.setenv("PATH", str(tmp_path))  # a PATH without ffmpeg on it
    mp4 = tmp_path / "flight.mp4"
    assert_user_error(quadnav("animate", flown, "-o", mp4), str(mp4), "needs ffmpeg", ".gif")
    assert not mp4.exists()


@pytest.mark.parametrize(("args", "fragments"), [
    (["-o", "{tmp}/flight.avi"], ["flight.avi", "expected a file name ending in .gif or .mp4"]),
    (["-o", "{tmp}/missing/flight.gif"], ["missing", "does not exist"]),
    (["--fps", "60", "-o", "{tmp}/flight.gif"], ["60 frames per second", "at most 50"]),
    (["--max-frames", "1"], ["--max-frames", "expected a whole number from 2 to 10,000"]),
    (["--speed", "0"], ["--speed", "expected from 0.01 to 1,000"]),
])
def test_bad_flags_are_one_line_exit_2(flown, tmp_path, args, fragments):
    args = [arg.format(tmp=tmp_path) for arg in args]
    assert_user_error(quadnav("animate", flown, *args), *fragments)
    assert list(tmp_path.iterdir()) == []


def test_bad_folders_are_one_line_exit_2(pathless, tmp_path):
    assert_user_error(run_here("animate", tmp_path / "nowhere", "-o", tmp_path / "a.gif"),
                      "nowhere", "not a quadnav fly or track output folder")
    assert_user_error(quadnav("animate", pathless, "-o", tmp_path / "a.gif"),
                      str(pathless), "no path", "no flight to animate")
    assert list(tmp_path.iterdir()) == []
