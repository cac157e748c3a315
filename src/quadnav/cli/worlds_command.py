"""``quadnav worlds`` and ``quadnav references``: the built-in worlds and references,
and their parameters."""

from __future__ import annotations

import argparse
from collections.abc import Sequence

from quadnav.cli.commands import command_help
from quadnav.specs import SpecInfo
from quadnav.world.builtin import DEFAULT_MARGIN, DEFAULT_WORLD_SPEC, describe_worlds


def print_specs(infos: Sequence[SpecInfo]) -> None:
    """Print each built-in thing: its name and summary, then its parameters with defaults,
    types, help and ranges, a blank line after each."""
    name_width = max(len(info.name) for info in infos) + 2
    for info in infos:
        print(f"{info.name:<{name_width}}{info.summary}")
        width = max((len(p.name) + len(p.default) + 1 for p in info.params), default=0)
        for p in info.params:
            print(f"    {p.name + '=' + p.default:<{width}}  {p.type:<6} {p.help}; {p.range}")
        print()


def worlds(args: argparse.Namespace) -> int:
    """Print every built-in world, a summary line, and its parameters with defaults and
    ranges."""
    print_specs(describe_worlds())
    print(f"Use a world wherever a MAP is accepted, e.g. {DEFAULT_WORLD_SPEC}:seed=3 or "
          "forest:size=50x50x8,density=0.05,seed=3.")
    print(f"Each has a default start and goal, proven connected at a {DEFAULT_MARGIN:g} m margin.")
    return 0


def add_worlds_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav worlds`` on the top-level subparsers."""
    parser = subparsers.add_parser("worlds", help=command_help("worlds"),
                                   description="List the built-in worlds and their parameters.")
    parser.set_defaults(handler=worlds)


def references(args: argparse.Namespace) -> int:
    """Print every built-in reference, a summary line, and its parameters with defaults
    and ranges."""
    from quadnav.trajectory.references.builtin import describe_references

    print_specs(describe_references())
    print("Fly one with quadnav track, e.g. quadnav track step:axis=z,size=0.5 or "
          "quadnav track helix:radius=2,speed=1.5.")
    print("Each starts at rest at (0, 0, height), keeps the yaw at 0 and ends at rest; the "
          "shapes speed up and slow down smoothly over 'ramp' seconds.")
    return 0


def add_references_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav references`` on the top-level subparsers."""
    parser = subparsers.add_parser(
        "references", help=command_help("references"),
        description="List the built-in references that quadnav track flies, and their "
                    "parameters.")
    parser.set_defaults(handler=references)
