"""``quadnav worlds``: the built-in worlds and their parameters."""

from __future__ import annotations

import argparse

from quadnav.world.builtin import DEFAULT_MARGIN, DEFAULT_WORLD_SPEC, describe_worlds


def worlds(args: argparse.Namespace) -> int:
    """Print every built-in world, a summary line, and its parameters with defaults and
    ranges."""
    for info in describe_worlds():
        print(f"{info.name:<8}{info.summary}")
        width = max((len(p.name) + len(p.default) + 1 for p in info.params), default=0)
        for p in info.params:
            print(f"    {p.name + '=' + p.default:<{width}}  {p.type:<6} {p.help}; {p.range}")
        print()
    print(f"Use a world wherever a MAP is accepted, e.g. {DEFAULT_WORLD_SPEC}:seed=3 or "
          "forest:size=50x50x8,density=0.05,seed=3.")
    print(f"Each has a default start and goal, proven connected at a {DEFAULT_MARGIN:g} m margin.")
    return 0


def add_worlds_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav worlds`` on the top-level subparsers."""
    parser = subparsers.add_parser("worlds", help="list the built-in worlds and their parameters",
                                   description="List the built-in worlds and their parameters.")
    parser.set_defaults(handler=worlds)
