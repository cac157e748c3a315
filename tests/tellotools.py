"""Flying quadnav's Tello bridge against the emulator, for the Tello tests.

djitellopy's sockets live in a network namespace private to the test process
(:func:`~quadnav.hardware.emulator.server.djitellopy_namespace`, the ``client_ns`` fixture), so
parallel workers never share port 8889. What the drone really did is read from the
emulator: its track (world frame) and the commands it heard.
"""

from __future__ import annotations

import time
from functools import cache
from pathlib import Path

import numpy as np
import pytest

from quadnav.hardware.bridge.flight import BridgeSettings, Flown, fly
from quadnav.hardware.bridge.flight_plan import FlightPlan, plan_flight
from quadnav.hardware.emulator.netns import unavailable_reason
from quadnav.planning import PlannerSettings
from quadnav.trajectory.generate import TrajectorySettings
from quadnav.world import World, load_world, read_start_goal

MAP = "rbe595/p2b_map1.txt"
START_GOAL = "rbe595/p2b_startandgoal_map1.txt"
MARGIN = 0.2
NO_NETNS = unavailable_reason()
needs_netns = pytest.mark.skipif(NO_NETNS is not None, reason=NO_NETNS or "")
#: A 6 x 2 x 1.5 m room, and a flight along it at the takeoff height: planned in a moment,
#: one long ``go`` move, or ``rc`` sticks that a lost link could carry to its far wall.
ROOM = "boundary 0 0 0 6 2 1.5\n"
ROOM_START = (0.5, 1.0, 0.8)
ROOM_GOAL = (3.5, 1.0, 0.8)


@cache
def planned_course(folder: Path):
    """The RBE595 course map, its start and goal, and their planned flight (yaw 0), planned
    once per test process."""
    world = load_world(folder / MAP)
    start, goal = read_start_goal(folder / START_GOAL)
    plan = plan_flight(world, start, goal, MARGIN, 0.0,
                       planning=PlannerSettings(seed=0, max_iterations=50_000, time_limit=10),
                       trajectory=TrajectorySettings(v_max=0.5, a_max=1.0))
    return world, start, goal, plan


@cache
def planned_room() -> FlightPlan:
    """The flight along :data:`ROOM`, planned once per test process."""
    room = World(np.array([float(v) for v in ROOM.split()[1:]]), name="room")
    return plan_flight(room, ROOM_START, ROOM_GOAL, MARGIN, 0.0,
                       planning=PlannerSettings(seed=0, max_iterations=300, time_limit=5),
                       trajectory=TrajectorySettings(v_max=0.5, a_max=1.0))


def emulated_flight(plan: FlightPlan, client_ns, folder, mode="waypoints", scale=10.0,
                    **emulator) -> tuple[Flown, object]:
    """Fly ``plan`` on an emulator standing under its start, which writes its true track to
    a file beside ``folder`` for the bridge to read after the flight; returns what the
    bridge flew (its outcome, dead-reckoned track and the true track) and the emulator
    (stopped) once the drone has come to rest."""
    from quadnav.hardware.emulator.server import TelloEmulator

    folder = Path(folder)
    truth = folder.with_name(f"{folder.name}-emulator-truth.csv")
    with TelloEmulator(start=tuple(plan.takeoff_ground), time_scale=scale,
                       client_netns=client_ns, truth=truth, **emulator) as drone:
        flown = fly(plan, BridgeSettings(mode=mode, time_scale=scale), folder,
                    host=drone.host, truth=truth)
        deadline = time.monotonic() + 5.0
        while drone.flying() and time.monotonic() < deadline:  # e.g. landing by itself
            time.sleep(0.02)
    return flown, drone


def assert_kept_the_fence(plan: FlightPlan, positions: np.ndarray) -> None:
    """Every position (N, 3) is inside the fence, or in the column of the takeoff or of
    the landing (which a safe stop makes where the drone is), and no block was touched."""
    fence = plan.fence
    on_columns = np.zeros(len(positions), dtype=bool)
    for ground in (plan.takeoff_ground, positions[-1]):
        on_columns |= np.linalg.norm(positions[:, :2] - ground[:2], axis=1) < 0.05
    inside = fence.contains(positions)
    assert (inside | on_columns).all(), positions[~(inside | on_columns)][:5]
    walls = fence.world.replace(boundary=fence.world.boundary + np.repeat([-1.0, 1.0], 3))
    assert walls.clearances(positions).min() >= MARGIN  # no block touched, margin kept


def assert_on_the_floor(drone, where=None) -> None:
    """The emulated drone has landed (within 5 cm of ``where`` (3,), if given)."""
    _, positions = drone.track()
    assert not drone.flying()
    assert positions[-1, 2] == pytest.approx(0.0, abs=1e-6)
    if where is not None:
        assert np.linalg.norm(positions[-1, :2] - np.asarray(where)[:2]) < 0.05
