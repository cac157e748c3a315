"""Monte-Carlo evaluation: many missions over a grid of maps, seeds, speeds, disturbances,
vehicle spreads, planners and gains, on local worker processes or on Ray.

* :mod:`.grid` — the spec (TOML or command line) and its missions, in a fixed order.
* :mod:`.fly_one` — one mission -> one row (never raises for the mission's own failure).
* :mod:`.executor` — any module-level function over items, locally or on Ray (generic).
* :mod:`.table` — the results table: schema, journal, Parquet and CSV.
* :mod:`.summary`, :mod:`.summary_page` — rates with Wilson intervals; summary.html.
* :mod:`.folder`, :mod:`.run` — a batch folder and a run into it (resumable).
"""
