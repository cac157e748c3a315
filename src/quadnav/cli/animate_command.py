"""``quadnav animate``: an animated GIF or MP4 of a run folder's flight."""

from __future__ import annotations

import argparse
from pathlib import Path

from quadnav.cli.args import number_in, output_path
from quadnav.cli.commands import command_help
from quadnav.cli.progress import fraction_bar
from quadnav.limits import Range
from quadnav.runs import read_run

#: The animation's file name in DIR when no -o is given.
DEFAULT_NAME = "flight.gif"
#: Most frames drawn by default (a longer flight plays faster), and frames per second.
MAX_FRAMES = 150
DEFAULT_FPS = 20.0
#: Relative excess of the playback speed over --speed that is worth a note.
SPEED_NOTE = 1.01
#: Ranges of --fps, --speed (flight seconds per second) and --max-frames.
FPS = Range(0.0, 120.0, "frames per second", above_low=True)
PLAYBACK = Range(0.01, 1000.0)
FRAMES = Range(2, 10_000, whole=True)


def animate(args: argparse.Namespace) -> int:
    """Write the animation; exit 0 (2 on bad input, before anything is drawn)."""
    from quadnav.viz.animation import save_animation

    run = read_run(args.folder)
    output = Path(args.output) if args.output else run.folder / DEFAULT_NAME
    with fraction_bar("animate", args.quiet) as progress:
        info = save_animation(run, output, args.fps, args.speed, args.max_frames, progress)
    print(f"wrote {output}: {info.frames} frames of {info.width} x {info.height} pixels "
          f"at {info.fps:.4g} fps, {info.speed:.3g}x real time")
    if info.speed > SPEED_NOTE * args.speed:
        print(f"  (faster than --speed {args.speed:g} to fit the flight in at most "
              f"{args.max_frames} frames; raise --max-frames or lower --fps for a slower "
              "replay)")
    return 0


def add_animate_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav animate`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "animate", help=command_help("animate"),
        description="An animation of the flight in DIR (written by quadnav fly or track -o DIR): "
                    "the map in 3D with the path and the trajectory, the flown track "
                    "growing, the drone (enlarged, turned by its recorded attitude) and the "
                    "flight time. A .gif is written with pillow; an .mp4 needs ffmpeg on "
                    "the PATH. Frames sample the flight evenly; a flight that needs more "
                    "than --max-frames frames plays faster than --speed (the command says "
                    "how fast). Exit 2 on bad input.")
    p.add_argument("folder", metavar="DIR", help="a quadnav fly or track output folder")
    p.add_argument("-o", "--output", type=output_path, metavar="FILE",
                   help="the animation to write, ending in .gif or .mp4 (default: "
                        f"DIR/{DEFAULT_NAME})")
    p.add_argument("--fps", type=number_in(FPS), default=DEFAULT_FPS, metavar="N",
                   help=f"frames per second, {FPS.describe()} (default: {DEFAULT_FPS:g}; a "
                        "GIF rounds it so that a frame lasts whole hundredths of a second, "
                        "at least two)")
    p.add_argument("--speed", type=number_in(PLAYBACK), default=1.0, metavar="X",
                   help=f"flight seconds per second of animation, {PLAYBACK.describe()} "
                        "(default: 1, real time)")
    p.add_argument("--max-frames", type=number_in(FRAMES), default=MAX_FRAMES, metavar="N",
                   help=f"most frames drawn, {FRAMES.describe()} (default: {MAX_FRAMES})")
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.set_defaults(handler=animate)
