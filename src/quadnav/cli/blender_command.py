"""``quadnav blender``: a run folder as a Blender scene (.blend), with optional stills."""

from __future__ import annotations

import argparse
from pathlib import Path

from quadnav.cli.args import output_path
from quadnav.cli.commands import command_help
from quadnav.runs import read_run
from quadnav.viz.blender_scene import (
    CAMERAS,
    DEFAULT_FPS,
    DEFAULT_SIZE,
    INSTALL_HINT,
    MAX_TREE_EDGES,
    write_blender,
)

#: Smallest and largest render width or height, pixels.
MIN_PIXELS, MAX_PIXELS = 16, 8192


def image_size(text: str) -> tuple[int, int]:
    """argparse type: ``WxH``, a width and height in pixels."""
    width, _, height = text.lower().partition("x")
    try:
        size = int(width), int(height)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected WIDTHxHEIGHT in pixels, e.g. 1280x720, "
                                         f"got {text!r}") from None
    if not all(MIN_PIXELS <= side <= MAX_PIXELS for side in size):
        raise argparse.ArgumentTypeError(f"expected a width and height from {MIN_PIXELS} to "
                                         f"{MAX_PIXELS} pixels, got {text!r}")
    return size


def frame_rate(text: str) -> int:
    """argparse type: whole frames per second, 1 to 240."""
    try:
        fps = int(text)
    except ValueError:
        fps = 0
    if not 1 <= fps <= 240:
        raise argparse.ArgumentTypeError(f"expected whole frames per second from 1 to 240, "
                                         f"got {text!r}")
    return fps


def blender(args: argparse.Namespace) -> int:
    """Build, save and render the scene; print what was written."""
    output = Path(args.output) if args.output else Path(args.folder) / "scene.blend"
    run = read_run(args.folder)
    info = write_blender(run, output, args.render, args.size, args.fps)
    tree = (f"tree {info.tree_edges:,} of {info.tree_edges_total:,} edges"
            if info.tree_edges < info.tree_edges_total else f"tree {info.tree_edges:,} edges")
    drone = (f"drone keyframed on {info.frames} frames at {info.fps} fps" if info.frames
             else "no flight")
    print(f"wrote {output} ({info.blocks} blocks, {tree}, {drone})"
          + "".join(f", {path}" for path in args.render))
    return 0


def add_blender_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav blender`` on the top-level subparsers."""
    p = subparsers.add_parser(
        "blender", help=command_help("blender"),
        description="Build a Blender scene of a quadnav fly or track output folder and save "
                    "it as a .blend: the blocks as cubes in their colours, the boundary as a black "
                    "box of alpha 0.344, the start (red) and goal (green) spheres, the "
                    f"explored tree (at most {MAX_TREE_EDGES:,} edges), the path (red), the "
                    "trajectory (orange) and a drone keyframed along the flight with its "
                    "recorded position and attitude. --render renders a still with "
                    "Blender's Workbench engine, headless. Needs Blender's Python module: "
                    f"{INSTALL_HINT}.")
    p.add_argument("folder", metavar="DIR", help="folder written by quadnav fly or track -o DIR")
    p.add_argument("-o", "--output", type=output_path, metavar="FILE.blend",
                   help="the .blend file to write (default: DIR/scene.blend)")
    p.add_argument("--render", action="append", default=[], metavar="NAME.png",
                   help="also render a still from the camera named by the file's stem: "
                        f"{' or '.join(name + '.png' for name in CAMERAS)} (oblique: an "
                        "elevated three-quarter view; top: top-down orthographic); repeatable")
    p.add_argument("--size", type=image_size, default=DEFAULT_SIZE, metavar="WxH",
                   help=f"render size in pixels (default: {DEFAULT_SIZE[0]}x{DEFAULT_SIZE[1]})")
    p.add_argument("--fps", type=frame_rate, default=DEFAULT_FPS, metavar="N",
                   help=f"animation frames per second of flight time (default: {DEFAULT_FPS})")
    p.set_defaults(handler=blender)
