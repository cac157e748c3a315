"""A planner of your own as a plain function, in one file: a graph search over a voxel grid
(the MEAM620 project's planner), named on the command line where it is, unregistered:

    quadnav fly course:meam620/grid_forest --start 1.25 1.25 1 --goal 3.25 5.25 1.5 \\
        --planner "examples/plain_planner.py:graph_search(resolution=0.25)"

A plain planner is ``planner(world, start, goal, margin, **kwargs) -> path (N, 3)``: the
real map (quadnav.world.World), the start and goal (3,) m, outside the margin, and the
margin in metres; the spec's keyword arguments follow. quadnav checks the path exactly
(from the start to the goal, every segment free in the map inflated by the margin) and
reports the first segment at fault instead of flying it. For a planner that uses
quadnav's budget, seed and progress bar and returns its tree, register it instead:
examples/custom_planner.py.

Run: python examples/plain_planner.py [RESOLUTION]   (default 0.25 m; flies grid_forest)
"""

import sys

import numpy as np
from scipy.sparse import coo_matrix
from scipy.sparse.csgraph import dijkstra
from scipy.spatial import cKDTree


def graph_search(world, start, goal, margin, resolution=0.25):
    """The shortest route from ``start`` to ``goal`` over the centres of a voxel grid,
    each joined to its 26 neighbours by the straight edges that keep the margin (exact
    segment checks in the inflated map); None when there is none."""
    free = world.inflate(margin)
    axes = [np.arange(low + resolution / 2, high, resolution)
            for low, high in zip(free.lower, free.upper, strict=True)]
    centres = np.stack(np.meshgrid(*axes, indexing="ij"), axis=-1).reshape(-1, 3)
    nodes = np.vstack([start, goal, centres[free.points_free(centres)]])
    pairs = cKDTree(nodes).query_pairs(1.01 * np.sqrt(3) * resolution, output_type="ndarray")
    pairs = pairs[free.segments_free(nodes[pairs])]
    lengths = np.linalg.norm(nodes[pairs[:, 0]] - nodes[pairs[:, 1]], axis=1)
    graph = coo_matrix((lengths, (pairs[:, 0], pairs[:, 1])), shape=(len(nodes),) * 2)
    cost, previous = dijkstra(graph, directed=False, indices=0, return_predecessors=True)
    if not np.isfinite(cost[1]):
        return None
    route = [1]
    while route[-1] != 0:
        route.append(previous[route[-1]])
    return nodes[route[::-1]]


if __name__ == "__main__":
    from quadnav.mission import MissionSettings, fly_mission
    from quadnav.world import load_world

    resolution = float(sys.argv[1]) if len(sys.argv) > 1 else 0.25
    world = load_world("course:meam620/grid_forest")  # shipped with quadnav
    settings = MissionSettings(planner=f"{__file__}:graph_search(resolution={resolution})")
    metrics = fly_mission(world, (1.25, 1.25, 1.0), (3.25, 5.25, 1.5), settings=settings
                          ).metrics()
    print(f"graph search at {resolution:g} m: success {metrics['success']}, path "
          f"{metrics['path_length_m']:.2f} m, margin kept {metrics['flight_margin_m']:.3f} m")
