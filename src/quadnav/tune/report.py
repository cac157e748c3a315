"""What a tuning run leaves in its folder: :func:`write_outputs`.

* ``gains.toml`` — the tuned gains, every key (``--gains DIR/gains.toml`` flies them);
* ``tune.json`` — the settings, the study, the best trial, each gain set's scores on the
  training and held-out sets and every flight's metrics;
* ``trials.csv`` — one row per completed trial: its number, objective and point;
* ``report.html`` — one offline page: the comparison on both sets, the objective against
  the trials, the tracking error of every held-out flight per gain set, the tuned values
  against the starting ones.

All of them reach the folder together (:func:`~quadnav.runfolder.replaced_folder`); the
study's own storage (``study.db``) is left as it is.
"""

from __future__ import annotations

import json
from pathlib import Path
from typing import Any

import numpy as np
from matplotlib.figure import Figure

from quadnav.config import toml_text
from quadnav.pages import figure, render
from quadnav.report.html_report import png_bytes
from quadnav.runfolder import replaced_folder
from quadnav.trajectory.references.export import csv_table
from quadnav.tune.evaluate import (
    FAILURE_PENALTY,
    OVERSHOOT_ALLOWED,
    OVERSHOOT_WEIGHT,
    SATURATION_WEIGHT,
)
from quadnav.tune.run import OWN, TUNED, Outcome, TuneRun
from quadnav.viz.figures import new_figure

#: Every file a tuning run writes.
TUNE_FILES = ("gains.toml", "tune.json", "trials.csv", "report.html")
CM_PER_M = 100.0


def write_outputs(tuning: TuneRun, outcome: Outcome, folder: Path) -> list[str]:
    """Write :data:`TUNE_FILES` of ``outcome`` into ``folder``, whole or not at all."""
    record = tuning.record(outcome)
    comment = (f"Gains tuned by quadnav tune for the {record['vehicle']} vehicle: trial "
               f"{outcome.best_trial} of {record['trials']} ({record['space']} space, "
               f"{tuning.settings.study.sampler}, seed {tuning.settings.study.seed}), "
               f"training set {record['training']}.")
    knobs = record["knobs"]
    trials = [[trial.number, trial.value, *(trial.params[k] for k in knobs)]
              for trial in outcome.trials]
    texts = {"gains.toml": toml_text(outcome.tuned, comment),
             "tune.json": json.dumps(record, indent=2) + "\n",
             "trials.csv": csv_table(np.array(trials, dtype=float).reshape(-1, 2 + len(knobs)),
                                     ",".join(["trial", "objective", *knobs])),
             "report.html": _page(tuning, outcome, record)}
    with replaced_folder(folder, TUNE_FILES) as staging:
        for name, text in texts.items():
            (staging / name).write_text(text, encoding="utf-8")
    return list(texts)


def comparison_rows(outcome: Outcome, set_name: str) -> list[list[str]]:
    """One row per gain set of ``set_name``'s scores: name, successes, median and largest
    RMS error (cm), mean step overshoot (%), objective — for the page and the terminal."""
    rows = []
    for name, s in outcome.scores[set_name].items():
        overshoot = s["mean_overshoot_percent"]
        rows.append([name, f"{s['successes']}/{s['flights']}",
                     f"{CM_PER_M * s['median_rms_tracking_error_m']:.2f}",
                     f"{CM_PER_M * s['max_rms_tracking_error_m']:.2f}",
                     "-" if overshoot is None else f"{overshoot:.2f}",
                     f"{s['objective']:.3f}"])
    return rows


COMPARISON_HEADER = ("gains", "successes", "median RMS error (cm)", "max RMS error (cm)",
                     "mean step overshoot (%)", "objective")


def _history_figure(outcome: Outcome) -> Figure:
    """Each trial's objective and the best so far, against the trial number."""
    numbers = np.array([trial.number for trial in outcome.trials])
    values = np.array([trial.value for trial in outcome.trials])
    fig = new_figure((9, 3.6))
    ax = fig.subplots()
    ax.plot(numbers, values, "o", color="tab:blue", markersize=3.5, alpha=0.7, label="trial")
    ax.step(numbers, np.minimum.accumulate(values), where="post", color="tab:red",
            label="best so far")
    ax.axhline(values[numbers == 0][0] if (numbers == 0).any() else values[0], color="0.4",
               linestyle="--", linewidth=0.8, label="starting gains (trial 0)")
    ax.set_ylim(top=min(values.max(), np.median(values) + 3 * (np.median(values)
                                                                - values.min() + 0.1)))
    ax.set_xlabel("trial")
    ax.set_ylabel("objective (training set)")
    ax.grid(alpha=0.3)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9)
    return fig


def _errors_figure(outcome: Outcome, items: list[str]) -> Figure:
    """The RMS tracking error of every held-out flight, per gain set (log scale), failed
    flights crossed."""
    flights = outcome.flights["held-out"]
    names = list(flights)
    fig = new_figure((11, 0.32 * len(items) + 1.6))
    ax = fig.subplots()
    rows = np.arange(len(items))
    for name in names:
        errors = np.array([CM_PER_M * m["rms_tracking_error_m"] for m in flights[name]])
        failed = np.array([not m["success"] for m in flights[name]])
        style = ({"marker": "D", "color": "black", "markersize": 6} if name == TUNED else
                 {"marker": "o", "markersize": 4, "alpha": 0.75})
        line, = ax.plot(errors, rows, linestyle="", label=name, zorder=3 + (name == TUNED),
                        **style)
        ax.plot(errors[failed], rows[failed], "x", color=line.get_color(), markersize=9,
                zorder=5)
    ax.set_yticks(rows, items, fontsize=7)
    ax.invert_yaxis()
    ax.set_xscale("log")
    ax.set_xlabel("RMS tracking error (cm); x: the flight failed")
    ax.grid(alpha=0.3, which="both")
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=8)
    return fig


def _page(tuning: TuneRun, outcome: Outcome, record: dict[str, Any]) -> str:
    """report.html: the gain sets compared on both sets, the study's progress, the tuned
    values against the starting ones."""
    return render(
        "tune.html", title=f"quadnav tune: {record['vehicle']}", vehicle=record["vehicle"],
        trials=len(outcome.trials), study=tuning.settings.study, space=tuning.settings.space,
        knobs=len(record["knobs"]), training=record["training"], held_out=record["held_out"],
        best_trial=outcome.best_trial, best_value=outcome.best_value,
        wall_time=outcome.wall_time,
        weights={"overshoot": OVERSHOOT_WEIGHT, "overshoot_allowed": OVERSHOOT_ALLOWED,
                 "saturation": SATURATION_WEIGHT, "failure": FAILURE_PENALTY},
        comparison_header=COMPARISON_HEADER,
        held_out_rows=comparison_rows(outcome, "held-out"),
        training_rows=comparison_rows(outcome, "training"),
        errors_figure=figure(png_bytes(_errors_figure(outcome, outcome.items["held-out"])),
                             "RMS tracking error of each held-out flight with each gain set."),
        history_figure=figure(png_bytes(_history_figure(outcome)),
                              "The objective of each trial on the training set, and the best "
                              "so far."),
        own=OWN, tuned=TUNED,
        values=[(name, f"{_start_value(tuning, name):.4g}", f"{value:.4g}")
                for name, value in outcome.best_params.items()],
        attitude_kp=str(outcome.tuned.attitude_kp.tolist()))


def _start_value(tuning: TuneRun, name: str) -> float:
    knob = next(knob for knob in tuning.knobs if knob.name == name)
    return knob.read(tuning.start)
