"""Where a start or goal lies: free, inside the margin, inside a block, outside."""

from __future__ import annotations

import pytest

from quadnav.errors import QuadnavError
from quadnav.world import World
from quadnav.world.placement import Placement, classify_point

WORLD = World(boundary=[0, 0, 0, 10, 10, 5], blocks=[[4, 4, 0, 6, 6, 5], [5, 5, 0, 7, 7, 5]])


@pytest.mark.parametrize(("point", "placement", "detail"), [
    ((2, 2, 2), Placement.FREE, "free, 2 m from the nearest obstacle"),
    ((0, 2, 2), Placement.IN_MARGIN, "(on the boundary)"),
    ((0.1, 2, 2), Placement.IN_MARGIN, "(near the boundary)"),
    ((3.9, 5, 2), Placement.IN_MARGIN, "(near block 0 [4, 6] x [4, 6] x [0, 5])"),
    ((5.5, 5.5, 2), Placement.IN_BLOCK, "inside block 0 [4, 6] x [4, 6] x [0, 5], block 1"),
    ((6, 5, 2), Placement.IN_BLOCK, "inside block 0"),  # on a face is inside
    ((11, 2, 2), Placement.OUTSIDE, "outside the boundary [0, 10] x [0, 10] x [0, 5]"),
])
def test_classify_point(point, placement, detail):
    report = classify_point(WORLD, point, 0.3, "start")
    assert report.placement is placement
    assert detail in report.detail
    assert report.usable == (placement in (Placement.FREE, Placement.IN_MARGIN))
    assert str(report).startswith("start (")


def test_on_the_boundary_is_in_the_margin_even_with_no_margin():
    assert classify_point(WORLD, (0, 2, 2), 0.0).placement is Placement.IN_MARGIN


def test_a_bad_point_is_a_user_error():
    with pytest.raises(QuadnavError, match="goal: expected 3 finite numbers"):
        classify_point(WORLD, (1, 2), 0.3, "goal")
