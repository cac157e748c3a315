"""Figures: 3D views of worlds, plans, trajectories and flights, drawn with matplotlib.

Every figure is made without pyplot and drawn off-screen by an Agg canvas of its own
(:func:`~quadnav.viz.figures.new_figure`), so drawing one leaves a user's pyplot session
and backend alone, and needs no display.
"""
