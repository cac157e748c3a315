"""Figures: 3D views of worlds (and, later, plans and flights).

Figures are drawn off-screen (matplotlib's Agg backend), so no display is needed.
"""

import matplotlib

matplotlib.use("Agg")
