"""Plan a path with RRT* through a built-in world and print what the search did.

Run: python examples/plan.py
"""

from quadnav.planning import PlannerSettings, make_problem, plan
from quadnav.world import load_world

world = load_world("forest:seed=3")  # a built-in world, with its own start and goal
problem = make_problem(world, world.start, world.goal, margin=0.2)
result = plan(problem, PlannerSettings(seed=1, max_iterations=20_000))
print(f"{result.message or 'solved'}: {len(result.path)} vertices, {result.length:.2f} m, "
      f"{result.stats.nodes} tree nodes in {result.stats.seconds:.2f} s")
