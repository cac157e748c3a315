"""Keeping a trajectory clear of the blocks: collision checks and refinement until free
(:mod:`.collision`), safe corridors around a path (:mod:`.corridor`), and the safe space
with the margin a trajectory keeps, measured exactly (:mod:`.space`)."""
