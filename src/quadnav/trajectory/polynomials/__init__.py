"""The generators' piecewise polynomials through waypoints at given times: the shared
basis and cost matrices (:mod:`.basis`), the clamped cubic spline, quintic segments,
minimum snap (or jerk) in closed form and as a QP with corridors and limits."""
