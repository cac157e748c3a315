"""``quadnav tune``: the cascade's gains tuned by an Optuna search, compared on held-out
flights with the vehicle's own gains and the course's gain tables."""

from __future__ import annotations

import argparse
import sys

from quadnav.cli.args import (
    add_executor_arguments,
    number_in,
    output_path,
    seed_value,
    workers_description,
)
from quadnav.cli.commands import command_help
from quadnav.errors import QuadnavError
from quadnav.limits import Range
from quadnav.runfolder import check_output_folder
from quadnav.vehicle.params import DEFAULT_PRESET, vehicle_forms

#: Trials a study may hold, and trials asked at once.
TRIALS = Range(1, 100_000, whole=True)
PARALLEL = Range(1, 1024, whole=True)
DEFAULT_TRIALS = 100
DEFAULT_PARALLEL = 4
DEFAULT_STUDY = "quadnav-tune"


def _import_tuning():
    """The tuner's modules (Optuna is the optional ``quadnav[tune]``)."""
    try:
        import optuna  # noqa: F401
    except ImportError:
        raise QuadnavError("quadnav tune needs the optional Optuna package: "
                           "python -m pip install 'quadnav[tune]'") from None
    from quadnav.tune import report, run, study

    return report, run, study


def tune(args: argparse.Namespace) -> int:
    """Tune, compare, write the folder; exit 0 when the study is done."""
    from quadnav.control.gains import course_gain_names

    report, run, study = _import_tuning()
    folder = check_output_folder(args.output)
    if args.sampler == "cmaes":
        _check_cmaes()
    settings = run.TuneSettings(
        vehicle=args.params, gains=args.gains, space=args.space,
        study=study.StudySettings(trials=args.trials, sampler=args.sampler, seed=args.seed,
                                  storage=args.storage or run.default_storage(folder),
                                  name=args.study, parallel=args.parallel),
        training=args.train, held_out=args.test,
        compare=tuple(course_gain_names() if args.compare is None else args.compare))
    tuning = run.TuneRun(settings)
    if args.storage is None:
        folder.mkdir(parents=True, exist_ok=True)
    items = tuning.plan()
    print(f"tuning {len(tuning.knobs)} gains of the {tuning.vehicle.name} vehicle on "
          f"{len(items['training'])} training flights ({args.train}), comparing on "
          f"{len(items['held-out'])} held-out flights ({args.test}); "
          + workers_description(args).format(s="s") + "; study "
          f"{settings.study.name!r} in {settings.study.storage}", flush=True)
    try:
        with _TrialBar(args, settings.study) as on_round:
            outcome = tuning.run(items, args.workers, args.ray is not None, args.ray or None,
                                 on_round)
    except KeyboardInterrupt:
        print(f"quadnav: the study keeps its finished trials in {settings.study.storage}; "
              "run the same command again to resume", file=sys.stderr)
        raise
    written = report.write_outputs(tuning, outcome, folder)
    _print_comparison(report, outcome)
    print(f"best: trial {outcome.best_trial} of {len(outcome.trials)}, objective "
          f"{outcome.best_value:.3f}; wall time {outcome.wall_time:.0f} s")
    print("wrote " + ", ".join(str(folder / name) for name in written))
    return 0


def _check_cmaes() -> None:
    try:
        import cmaes  # noqa: F401
    except ImportError:
        raise QuadnavError("--sampler cmaes needs the cmaes package: "
                           "python -m pip install 'quadnav[tune]'") from None


class _TrialBar:
    """A progress bar of completed trials with the best objective so far; yields the
    study's round callback."""

    def __init__(self, args: argparse.Namespace, settings) -> None:
        self.quiet = args.quiet
        self.total = settings.trials
        self.bar = None

    def __enter__(self):
        return self.round

    def round(self, study) -> None:
        from optuna.trial import TrialState

        from quadnav.cli.progress import terminal_bar

        done = len(study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)))
        if self.bar is None:
            self.bar = terminal_bar(self.quiet, total=self.total, desc="trials", unit="trial",
                                    leave=False)
        self.bar.set_postfix_str(f"best {study.best_value:.3f}", refresh=False)
        self.bar.update(done - self.bar.n)

    def __exit__(self, *exc) -> None:
        if self.bar is not None:
            self.bar.close()


def _print_comparison(report, outcome) -> None:
    for set_name in ("held-out", "training"):
        rows = report.comparison_rows(outcome, set_name)
        widths = [max(len(str(row[k])) for row in [report.COMPARISON_HEADER, *rows])
                  for k in range(len(rows[0]))]
        print(f"{set_name} set:")
        for row in [report.COMPARISON_HEADER, *rows]:
            print("  " + "  ".join(str(cell).ljust(width) for cell, width
                                   in zip(row, widths, strict=True)).rstrip())


def add_tune_command(subparsers: argparse._SubParsersAction) -> None:
    """Register ``quadnav tune`` on the top-level subparsers."""
    from quadnav.control.gains import course_gain_names

    p = subparsers.add_parser(
        "tune", help=command_help("tune"),
        description="Search the cascade's gains (Optuna: TPE or CMA-ES) for a vehicle against "
                    "a training set of references and missions, then compare the vehicle's "
                    "own gains, the course's gain tables and the tuned gains on a held-out "
                    "set. Writes DIR/gains.toml (fly it with --gains), DIR/tune.json, "
                    "DIR/trials.csv and DIR/report.html; the study is kept in DIR/study.db "
                    "(or --storage), so an interrupted study resumes. Exit 0 when done, 2 on "
                    "bad input, 130/143 when stopped.")
    p.add_argument("--params", default=DEFAULT_PRESET, metavar="NAME|FILE",
                   help=f"vehicle: {vehicle_forms()} (default: {DEFAULT_PRESET})")
    p.add_argument("--gains", metavar="NAME|FILE",
                   help="starting gains: a TOML file or a course gain table (default: the "
                        "vehicle's own)")
    p.add_argument("--space", choices=("cascade", "outer"), default="cascade",
                   help="cascade: the position and velocity PIDs, attitude, roll/pitch rate "
                        "PID and tilt limit (18 knobs); outer: the 18 position and velocity "
                        "gains, x and y shared (12 knobs) (default: cascade)")
    p.add_argument("--trials", type=number_in(TRIALS), default=DEFAULT_TRIALS, metavar="N",
                   help=f"trials the study holds when done, {TRIALS.describe()}; a resumed "
                        f"study counts those it has (default: {DEFAULT_TRIALS})")
    p.add_argument("--sampler", choices=("tpe", "cmaes"), default="tpe",
                   help="Optuna's sampler (default: tpe)")
    p.add_argument("--seed", type=seed_value, default=0, metavar="N",
                   help="the sampler's seed; the same seed and --parallel give the same "
                        "study, locally or on Ray (default: 0)")
    p.add_argument("--parallel", type=number_in(PARALLEL), default=DEFAULT_PARALLEL,
                   metavar="K", help=f"trials asked and flown together, {PARALLEL.describe()} "
                                     f"(default: {DEFAULT_PARALLEL})")
    p.add_argument("--train", default="training", metavar="SET",
                   help="the set tuned on: a TOML file, or a shipped set (training, "
                        "held-out) (default: training)")
    p.add_argument("--test", default="held-out", metavar="SET",
                   help="the set the gains are compared on (default: held-out)")
    p.add_argument("--compare", nargs="*", metavar="NAME|FILE",
                   help="gain tables compared besides the vehicle's own and the tuned gains "
                        f"(default: every course table: {', '.join(course_gain_names())})")
    p.add_argument("--storage", metavar="URL",
                   help="Optuna RDB storage, e.g. postgresql://user@host/db for a study shared "
                        "by several machines (default: sqlite:///DIR/study.db)")
    p.add_argument("--study", default=DEFAULT_STUDY, metavar="NAME",
                   help=f"the study's name in the storage (default: {DEFAULT_STUDY})")
    add_executor_arguments(p)
    p.add_argument("--quiet", action="store_true", help="no progress bar")
    p.add_argument("-o", "--output", type=output_path, default="tune", metavar="DIR",
                   help="folder to write into, created if needed (default: tune)")
    p.set_defaults(handler=tune)

