"""Figures: 3D views of worlds, plans, trajectories and flights, drawn with matplotlib.

Importing this package leaves matplotlib's backend alone (a user's session keeps its
own); the ``quadnav`` command draws off-screen with the Agg backend (``MPLBACKEND``),
so it needs no display.
"""
