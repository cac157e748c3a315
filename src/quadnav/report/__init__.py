"""Report stage: the folder a run writes (:mod:`.rundir`), read back for viewers and reports."""
