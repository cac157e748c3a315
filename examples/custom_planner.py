"""A planner of your own, in one file: a probabilistic roadmap (PRM) registered by name and
flown through a course map with the rest of quadnav's pipeline.

A planner is a function ``planner(problem, settings, progress) -> PlanResult`` that
searches ``problem.free_world`` (the map with its blocks grown by the margin) from
``problem.search_start`` to ``problem.search_goal``; ``problem.full_path`` adds the
short legs out of the margin. Use this file as a template. (A plain function
``(world, start, goal, margin) -> path`` needs no registering: examples/plain_planner.py.)

Run: python examples/custom_planner.py [MAP]   (a map with its own start and goal, such as
course:meam620/test_window, after quadnav maps fetch meam620/test_window; default: the
built-in forest)
"""

import sys
import time
from pathlib import Path

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree

from quadnav.mission import MissionSettings, fly_mission
from quadnav.planning import PlanResult, PlanStats, path_length, register_planner
from quadnav.world import load_world

SAMPLES = 1500  # roadmap vertices besides the start and the goal
NEIGHBOURS = 12  # edges tried from each vertex


def plan_prm(problem, settings, progress=None) -> PlanResult:
    """Sample free points, join each to its nearest neighbours by free straight edges
    (exact segment checks), and take the shortest route from start to goal."""
    began = time.perf_counter()
    free = problem.free_world
    points = np.vstack([problem.search_start, problem.search_goal,
                        free.sample_free(SAMPLES, seed=settings.seed)])
    distances, neighbours = cKDTree(points).query(points, NEIGHBOURS + 1)
    rows = np.repeat(np.arange(len(points)), NEIGHBOURS)
    cols, lengths = neighbours[:, 1:].ravel(), distances[:, 1:].ravel()
    free_edges = free.segments_free(np.hstack([points[rows], points[cols]]).reshape(-1, 2, 3))
    graph = coo_matrix((lengths[free_edges], (rows[free_edges], cols[free_edges])),
                       shape=(len(points), len(points)))
    cost, previous = dijkstra(graph, directed=False, indices=0, return_predecessors=True)
    route = [1]
    while np.isfinite(cost[1]) and route[-1] != 0:
        route.append(previous[route[-1]])
    solved = bool(np.isfinite(cost[1]))
    path = problem.full_path(points[route[::-1]]) if solved else np.zeros((0, 3))
    stats = PlanStats(iterations=SAMPLES, nodes=len(points),
                      seconds=time.perf_counter() - began, time_to_first=None,
                      cost_history=[[0.0, path_length(path)]] if solved else [])
    return PlanResult("prm", solved, path, points, np.full(len(points), -1), stats,
                      settings.seed, "" if solved else "the roadmap does not join them")


register_planner("prm", plan_prm)

if __name__ == "__main__":
    name = sys.argv[1] if len(sys.argv) > 1 else "forest"
    world = load_world(name)  # flown from its own start to its own goal
    mission = fly_mission(world, settings=MissionSettings(planner="prm"))
    metrics = mission.metrics()
    print(f"{Path(name).name} by PRM: success {metrics['success']}, path "
          f"{metrics['path_length_m']:.2f} m, flight {metrics['flight_time_s']:.1f} s, "
          f"least clearance {metrics['min_clearance_m']:.3f} m")
