"""Writing a whole run folder (:mod:`quadnav.runs`): its text files, then the figures,
the report and the interactive page drawn from them."""

from __future__ import annotations

from pathlib import Path

from quadnav.mission import Mission
from quadnav.missionconfig import MissionConfig
from quadnav.runfolder import replaced_folder
from quadnav.runs import (
    REPORT,
    RUN_FILES,
    VIEW_PAGE,
    RunContent,
    read_run,
    run_content,
    write_run_files,
)
from quadnav.tracking import Tracking


def write_run(run: Mission | Tracking | RunContent, folder: str | Path, figures: bool = True,
              html: bool = False, config: MissionConfig | None = None) -> list[str]:
    """Write the run folder of ``run`` (a mission, a tracking or their
    :func:`run_content`; the folder is created if needed), whole or not at all
    (:func:`~quadnav.runfolder.replaced_folder`); returns the names written. A mission
    built from ``config`` gets its mission.toml, which flies it again.

    The text files are written first; the new files are then read back once
    (:func:`read_run`) and, with ``figures``, the figures and the report are drawn from
    them, as every other consumer draws them; with ``html``, the interactive page too. All
    of them reach ``folder`` together at the end, and the files of an earlier run that this
    one does not write are removed then, so the folder never mixes two runs; an interrupted
    or failed write leaves it as it was."""
    folder = Path(folder)
    content = run if isinstance(run, RunContent) else run_content(run, config)
    with replaced_folder(folder, RUN_FILES) as staging:
        return _write_files(content, staging, folder, figures, html)


def _write_files(content: RunContent, staging: Path, folder: Path, figures: bool,
                 html: bool) -> list[str]:
    """Write the files of :func:`write_run` into the empty ``staging`` folder; the report
    names ``folder`` as the run's."""
    written = write_run_files(content, staging)
    if not (figures or html):
        return written
    run = read_run(staging)
    if figures:  # plotting is imported only when drawn: --no-figures runs never load it
        from quadnav.report.html_report import write_report
        from quadnav.viz.figures import collector_spared, save_figure
        from quadnav.viz.flight_figures import figure_makers

        makers = figure_makers(run)
        with collector_spared():
            for name, make in makers.items():
                save_figure(make(run), staging / name)
        write_report([run], staging / REPORT, shown=[folder])
        written += [*makers, REPORT]
    if html:
        from quadnav.viz.html_viewer import write_viewer

        write_viewer(run, staging / VIEW_PAGE)
        written.append(VIEW_PAGE)
    return written
