"""Report stage: a whole run folder written with its figures and pages (:mod:`.run_writer`),
and the HTML report of run folders (:mod:`.html_report`). The folder itself is
:mod:`quadnav.runs`."""
