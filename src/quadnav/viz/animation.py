"""An animation of a run's flight (:class:`~quadnav.runs.Run`): the map in 3D
with the path and the trajectory, the flown track growing, the drone (its arms turned by
the recorded attitude) and the flight time, as a GIF (pillow) or an MP4 (ffmpeg).

Frames sample the flight evenly, a bounded number of them, and the still scene is drawn
once, so an animation takes seconds whatever the flight's length.
"""

from __future__ import annotations

import io
import math
import shutil
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path

import numpy as np
from matplotlib.animation import AbstractMovieWriter, FFMpegWriter, FuncAnimation
from matplotlib.artist import Artist
from matplotlib.backends.backend_agg import FigureCanvasAgg
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from PIL import Image

from quadnav.errors import QuadnavError
from quadnav.files import atomic_output
from quadnav.runs import Run, run_outcome
from quadnav.vehicle.quaternion import to_matrix
from quadnav.viz.layout import finish
from quadnav.viz.map3d import draw_world, map_legend
from quadnav.viz.style import (
    DRONE_COLOR,
    DRONE_SCALE,
    FLOWN_COLOR,
    PATH_COLOR,
    TRAJECTORY_COLOR,
    outlined,
)

#: Highest GIF frame rate, frames per second: a GIF stores whole hundredths of a second
#: per frame, and viewers slow down frames shorter than 2/100 s.
MAX_GIF_FPS = 50.0
#: Size of the animation, inches, and its pixels per inch.
FIGURE_SIZE = (8.0, 6.0)
DPI = 100
#: Output formats by file name ending.
FORMATS = (".gif", ".mp4")
#: The drone's two arms (an X frame): (2, 2, 3) unit segments in the body frame.
_ARMS = np.array([[[-1.0, -1.0, 0.0], [1.0, 1.0, 0.0]],
                  [[-1.0, 1.0, 0.0], [1.0, -1.0, 0.0]]]) / math.sqrt(2.0)


@dataclass(frozen=True)
class AnimationInfo:
    """What :func:`save_animation` wrote: frames, frames per second, playback speed (flight
    seconds per second of animation), width and height in pixels."""

    frames: int
    fps: float
    speed: float
    width: int
    height: int


def frame_times(duration: float, fps: float, speed: float,
                max_frames: int) -> tuple[np.ndarray, float]:
    """Flight times of the frames, s, evenly spaced from 0 to ``duration`` (both
    included), and the playback speed they give at ``fps``: about ``speed``, raised when
    more than ``max_frames`` (>= 2) frames would be needed."""
    intervals = max(1, min(math.ceil(duration * fps / speed - 1e-9), max_frames - 1))
    return np.linspace(0.0, duration, intervals + 1), duration * fps / intervals


def check_animation_path(path: str | Path) -> str:
    """The format (``gif`` or ``mp4``) named by ``path``; QuadnavError for another
    ending, a missing folder, or an MP4 without ffmpeg on the PATH."""
    path = Path(path)
    suffix = path.suffix.lower()
    if suffix not in FORMATS:
        raise QuadnavError(f"{path}: expected a file name ending in {' or '.join(FORMATS)}")
    if not path.parent.is_dir():
        raise QuadnavError(f"{path}: folder {str(path.parent)!r} does not exist")
    if suffix == ".mp4" and shutil.which("ffmpeg") is None:
        raise QuadnavError(f"{path}: writing an MP4 needs ffmpeg on the PATH, and it was not "
                           "found; install ffmpeg or write a .gif")
    return suffix[1:]


def _scene(run: Run, size: tuple[float, float], dpi: float
           ) -> tuple[np.ndarray, Callable[[np.ndarray], np.ndarray]]:
    """The still part of every frame, drawn once at ``size`` inches and ``dpi``: the map
    (its box as large as its labels let it be), start and goal, path (outlined, so that
    it shows on red blocks), trajectory, the legend below and the title, as an RGBA
    image (H, W, 4); and the projection of points (N, 3), m, to that image's pixels
    (N, 2) from its bottom left corner."""
    world, metrics = run.world, run.metrics
    fig = Figure(figsize=size, dpi=dpi)
    canvas = FigureCanvasAgg(fig)
    ax = fig.add_axes((0.0, 0.08, 1.0, 0.84), projection="3d")
    handles = draw_world(ax, world, world.start, world.goal)
    if run.path is not None:
        handles += ax.plot(*run.path.T, color=PATH_COLOR, linewidth=1.4, linestyle="--",
                           zorder=20, path_effects=outlined(1.4), label="path")
    handles += ax.plot(*run.trajectory.position.T, color=TRAJECTORY_COLOR, linewidth=2.0,
                       alpha=0.6, zorder=21,
                       label="reference" if run.is_track else "trajectory")
    handles += [Line2D([], [], color=FLOWN_COLOR, linewidth=1.6, label="flown"),
                Line2D([], [], color=DRONE_COLOR, marker="o", linewidth=2.5,
                       label="drone (enlarged)")]
    ax.view_init(elev=30, azim=-60)
    map_legend(fig, world, handles, loc="lower left", ncol=4, frameon=False)
    fig.suptitle(f"{run.title}\n{run_outcome(metrics)}", fontsize=9)
    finish(fig)
    canvas.draw()
    image = np.array(canvas.buffer_rgba())
    projection, to_pixels = ax.get_proj(), ax.transData.frozen()

    def project(points: np.ndarray) -> np.ndarray:
        homogeneous = np.column_stack([points, np.ones(len(points))]) @ projection.T
        return to_pixels.transform(homogeneous[:, :2] / homogeneous[:, 3:])

    return image, project


class _Still(Artist):
    """An RGBA image (H, W, 4) of the figure's size pasted under everything else, pixel
    for pixel (quicker than an image artist, which resamples it on every draw)."""

    def __init__(self, image: np.ndarray) -> None:
        super().__init__()
        self._rows = np.ascontiguousarray(image[::-1])  # the renderer's rows run upwards

    def draw(self, renderer) -> None:
        gc = renderer.new_gc()
        renderer.draw_image(gc, 0, 0, self._rows)
        gc.restore()


def flight_animation(fig: Figure, run: Run, times: np.ndarray, fps: float) -> FuncAnimation:
    """The animation on ``fig`` of ``run``'s flight at the flight times ``times`` (F,), s,
    played at ``fps`` frames per second; each frame shows the last recorded sample at or
    before its time. The still scene is drawn once and the moving parts over it,
    projected the same way, so a frame costs milliseconds. ``run.flight`` must not be
    None."""
    flight = run.flight
    rows = np.clip(np.searchsorted(flight.t, times, side="right") - 1, 0, len(flight.t) - 1)
    image, project = _scene(run, tuple(fig.get_size_inches()), fig.dpi)
    fig.add_artist(_Still(image))
    height, width = image.shape[:2]
    ax = fig.add_axes((0.0, 0.0, 1.0, 1.0), xlim=(0, width), ylim=(0, height), zorder=1)
    ax.set_axis_off()
    track = project(flight.position)
    size = DRONE_SCALE * float(np.max(run.world.extent))
    (flown,) = ax.plot([], [], color=FLOWN_COLOR, linewidth=1.6)
    arms = [ax.plot([], [], color=DRONE_COLOR, linewidth=2.5)[0] for _ in _ARMS]
    (centre,) = ax.plot([], [], color=DRONE_COLOR, marker="o", markersize=6, linestyle="")
    clock = ax.text(width - 10, 10, "", ha="right", fontsize=11, family="monospace")

    def draw(frame: int) -> list:
        row = rows[frame]
        flown.set_data(*track[:row + 1].T)
        centre.set_data(*track[row:row + 1].T)
        turned = flight.position[row] + size * _ARMS @ to_matrix(flight.attitude[row]).T
        for arm, segment in zip(arms, turned, strict=True):
            arm.set_data(*project(segment).T)
        clock.set_text(f"t = {times[frame]:6.2f} s / {flight.t[-1]:.2f} s")
        return [flown, centre, *arms, clock]

    return FuncAnimation(fig, draw, frames=len(times), interval=1000.0 / fps,
                         cache_frame_data=False)


class _GifWriter(AbstractMovieWriter):
    """A GIF writer whose frames all take the first frame's palette: quick to encode,
    and frames that differ only where the drone moved stay small."""

    def setup(self, fig: Figure, outfile: str | Path, dpi: float | None = None) -> None:
        super().setup(fig, outfile, dpi)
        self._frames: list[Image.Image] = []

    def grab_frame(self, **savefig_kwargs) -> None:
        buffer = io.BytesIO()
        self.fig.savefig(buffer, format="rgba", dpi=self.dpi)
        frame = Image.frombuffer("RGBA", self.frame_size, buffer.getbuffer(), "raw", "RGBA",
                                 0, 1).convert("RGB")
        self._frames.append(frame.quantize(palette=self._frames[0], dither=Image.Dither.NONE)
                            if self._frames else frame.quantize())

    def finish(self) -> None:
        self._frames[0].save(self.outfile, format="GIF", save_all=True,
                             append_images=self._frames[1:], duration=1000 / self.fps, loop=0)


def gif_rate(fps: float) -> float:
    """The frame rate nearest ``fps`` that a GIF can play, frames per second: 100 over a
    whole number of hundredths; QuadnavError above :data:`MAX_GIF_FPS`."""
    if fps > MAX_GIF_FPS:
        raise QuadnavError(f"{fps:g} frames per second: a GIF plays at most "
                           f"{MAX_GIF_FPS:g}")
    return 100.0 / max(2, round(100.0 / fps))


def save_animation(run: Run, path: str | Path, fps: float, speed: float, max_frames: int,
                   progress: Callable[[float], None] | None = None) -> AnimationInfo:
    """Write the animation of ``run``'s flight to ``path`` (.gif or .mp4), whole or not at
    all, at ``fps`` frames per second (for a GIF, :func:`gif_rate`) and about ``speed``
    times real time (faster if the flight needs more than ``max_frames`` frames);
    ``progress`` is called with the fraction of frames drawn.

    Raises:
        QuadnavError: a bad output path (see :func:`check_animation_path`), a GIF rate
            too high, or a run without a flight.
    """
    path = Path(path)
    fmt = check_animation_path(path)
    if fmt == "gif":
        fps = gif_rate(fps)
    if run.flight is None:
        raise QuadnavError(f"{run.folder}: the run found no path, so there is no flight to "
                           "animate")
    times, played = frame_times(float(run.flight.t[-1]), fps, speed, max_frames)
    # A figure without pyplot: its canvas draws only when a frame is saved, once.
    fig = Figure(figsize=FIGURE_SIZE, dpi=DPI)
    animation = flight_animation(fig, run, times, fps)
    writer = _GifWriter(fps=fps) if fmt == "gif" else FFMpegWriter(fps=fps, codec="h264")

    def drawn(done: int, total: int) -> None:
        if progress is not None:
            progress((done + 1) / total)

    with atomic_output(path) as tmp:
        named = tmp.with_name(tmp.name + path.suffix)  # ffmpeg goes by the file's ending
        try:
            animation.save(named, writer=writer, progress_callback=drawn)
            named.replace(tmp)
        finally:
            named.unlink(missing_ok=True)
    width, height = (round(v) for v in fig.get_size_inches() * fig.dpi)
    return AnimationInfo(len(times), fps, played, width, height)
