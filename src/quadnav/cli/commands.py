"""The table of quadnav's commands, light enough to list them without loading any.

Each command lives in a module of :mod:`quadnav.cli` with a function that registers its
parser on the top-level subparsers. :func:`quadnav.cli.main.build_parser` imports only
the module of the command being run (``quadnav --help`` and ``--version`` import none), so
a command pays only for its own stack.
"""

from __future__ import annotations

from collections.abc import Sequence
from dataclasses import dataclass


@dataclass(frozen=True)
class Command:
    """One top-level command.

    Attributes:
        module: its module under :mod:`quadnav.cli`.
        register: the name of that module's function ``register(subparsers)``.
        help: the one-line help ``quadnav --help`` lists.
        aliases: other names that run it (``maps`` for ``map``).
    """

    module: str
    register: str
    help: str
    aliases: tuple[str, ...] = ()


#: Every top-level command, in the order ``quadnav --help`` lists them.
COMMANDS: dict[str, Command] = {
    "fly": Command("fly_command", "add_fly_command",
                   "plan, smooth and fly a simulated quadrotor through a map (the main job)"),
    "track": Command("track_command", "add_track_command",
                     "fly a given reference (a step, a helix, an MP.csv...) to tune gains"),
    "batch": Command("batch_command", "add_batch_command",
                     "fly many missions (maps x seeds x speeds ...) into a table and summary"),
    "compare": Command("compare_command", "add_compare_command",
                       "a batch's leaderboard: controllers, planners ... side by side, with "
                       "intervals and significance"),
    "refly": Command("refly_command", "add_refly_command",
                     "fly a run folder's mission, or one mission of a batch, again, with "
                     "figures"),
    "grade": Command("grade_command", "add_grade_command",
                     "grade a submission's own controller, planner or trajectory on a "
                     "course's maps and seeds, with a TA's report"),
    "tune": Command("tune_command", "add_tune_command",
                    "tune the controller's gains by an Optuna search (needs quadnav[tune])"),
    "animate": Command("animate_command", "add_animate_command",
                       "animate a flight from a quadnav fly or track output folder (GIF or MP4)"),
    "blender": Command("blender_command", "add_blender_command",
                       "a run folder as a Blender scene (.blend), with optional renders"),
    "map": Command("map_commands", "add_map_commands",
                   "inspect, check, draw and convert maps; list and fetch the public course "
                   "maps", aliases=("maps",)),
    "plan": Command("plan_command", "add_plan_command",
                    "plan a collision-free path (RRT* or OMPL)"),
    "report": Command("report_command", "add_report_command",
                      "write an HTML report of one or more quadnav fly or track output folders"),
    "traj": Command("traj_command", "add_traj_command",
                    "a smooth, timed trajectory through a path"),
    "view": Command("view_command", "add_view_command",
                    "write an interactive 3D page (HTML) of a quadnav fly or track output "
                    "folder"),
    "kino": Command("kino_command", "add_kino_command",
                    "kinodynamic RRT: a differential-drive robot or a quadrotor"),
    "worlds": Command("worlds_command", "add_worlds_command",
                      "list the built-in worlds and their parameters"),
    "references": Command("worlds_command", "add_references_command",
                          "list the built-in references of quadnav track and their parameters"),
    "tello": Command("tello_command", "add_tello_command",
                     "DJI Ryze Tello: emulate one, or fly a plan on one"),
}


def command_help(name: str) -> str:
    """The one-line help of the top-level command ``name``."""
    return COMMANDS[name].help


def command_in(argv: Sequence[str]) -> str | None:
    """The command the command line ``argv`` runs: its first word that is not an option
    (the top level has only ``--help`` and ``--version``, which take no value), if that
    names a command or one of its aliases; None when it does not."""
    word = next((word for word in argv if not word.startswith("-")), None)
    return next((name for name, command in COMMANDS.items()
                 if word == name or word in command.aliases), None)
