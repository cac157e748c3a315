"""Gain tuning by search, ``quadnav tune`` (the optional ``quadnav[tune]``: Optuna).

* :mod:`.space` — the knobs searched and gains from a point of the space;
* :mod:`.sets` — the training and held-out flights (references and missions);
* :mod:`.evaluate` — flying an item with some gains, and the objective;
* :mod:`.study` — the Optuna study, asked and told in rounds;
* :mod:`.run` — a whole run, from its inputs to the comparison;
* :mod:`.report` — the folder it leaves.
"""
