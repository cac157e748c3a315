"""Finishing a figure so that it can be handed in: 3D boxes that fit their axes, and
labels that collide with no other label, on every axes of a figure, 2D or 3D.

Matplotlib picks the ticks of a 3D axis without regard to how long the axis is drawn, so
on a long thin map the short axes crowd eight labels into a few pixels, and it scales a
3D box to a square axes whatever the box's shape, so a tall box pokes out of it (over
the title). :func:`finish` zooms each 3D box to fit and then, round by round, finds the
labels that overlap and rearranges those axes until none do. It lays the figure out
without drawing it, and leaves the layout fixed, so that saving the figure draws it once.

Legends are placed outside the axes by each figure (beside or below them, in the
figure's constrained layout), so they never cover data.
"""

from __future__ import annotations

from collections.abc import Iterator
from contextlib import contextmanager
from itertools import combinations

import numpy as np
from matplotlib import rc_context
from matplotlib.axes import Axes
from matplotlib.axis import Axis
from matplotlib.figure import Figure
from matplotlib.text import Text
from matplotlib.ticker import FixedLocator, MaxNLocator
from matplotlib.transforms import Bbox
from mpl_toolkits.mplot3d import Axes3D, proj3d

#: Clear space kept around every label, pixels.
LABEL_GAP = 2.0
#: Rounds of laying out and rearranging at most (each one halves a crowded axis' ticks,
#: so a handful suffices for any axis).
MAX_ROUNDS = 20
#: Tick steps allowed when thinning (matplotlib's defaults).
NICE_STEPS = (1, 2, 2.5, 5, 10)
#: Share of its axes' width or height (whichever binds) a 3D box's drawing with its
#: labels takes.
BOX_FILL = 0.98
#: Relative change of a 3D box's zoom too small to be worth another round.
ZOOM_TOLERANCE = 0.02
#: Change of an axes' place too small to be worth another round, pixels.
LAYOUT_TOLERANCE = 0.5


def _axes_axes(ax: Axes) -> list[Axis]:
    """The x, y (and z) axes of ``ax``."""
    return [ax.xaxis, ax.yaxis, *([ax.zaxis] if isinstance(ax, Axes3D) else [])]


def ticks_shown(axis: Axis) -> list[tuple[float, Text]]:
    """The ticks ``axis`` labels: (location in data units, label) of its major ticks
    inside its view interval, for each label shown (left or bottom, right or top) and
    not empty."""
    low, high = sorted(axis.get_view_interval())
    slack = 1e-9 * max(high - low, 1e-300)
    locations = axis.get_majorticklocs()
    return [(float(location), label)
            for location, tick in zip(locations, axis.get_major_ticks(len(locations)),
                                      strict=True)
            if low - slack <= location <= high + slack
            for label in (tick.label1, tick.label2) if label.get_visible() and label.get_text()]


def tick_labels(axis: Axis) -> list[Text]:
    """The tick labels ``axis`` draws (see :func:`ticks_shown`)."""
    return [text for _, text in ticks_shown(axis)]


def _box(text: Text, renderer) -> Bbox:
    return text.get_window_extent(renderer).padded(LABEL_GAP / 2)


def collisions(fig: Figure) -> list[tuple[Text, Text]]:
    """The pairs of labels of ``fig`` that overlap (with :data:`LABEL_GAP` between them),
    among the drawn tick labels and the axis labels of each of its axes. ``fig`` must
    have been laid out (:func:`lay_out`) or drawn."""
    renderer = fig.canvas.get_renderer()
    found = []
    for ax in fig.axes:
        texts = [text for axis in _axes_axes(ax)
                 for text in [*tick_labels(axis), axis.label] if text.get_text()]
        boxes = [_box(text, renderer) for text in texts]
        found += [(texts[i], texts[j]) for i, j in combinations(range(len(texts)), 2)
                  if boxes[i].overlaps(boxes[j])]
    return found


def box_corners(ax: Axes3D) -> np.ndarray:
    """(8, 2) pixels of the corners of ``ax``'s 3D box as drawn (after a draw or
    :func:`lay_out`)."""
    limits = (ax.get_xlim3d(), ax.get_ylim3d(), ax.get_zlim3d())
    corners = np.array(np.meshgrid(*limits, indexing="ij")).reshape(3, -1)
    x, y, _ = proj3d.proj_transform(*corners, ax.get_proj())
    return ax.transData.transform(np.column_stack([x, y]))


def _fit_box(ax: Axes3D) -> bool:
    """Zoom ``ax``'s 3D box as large as it fits: its drawing within :data:`BOX_FILL` of
    the axes (which matplotlib keeps square, and clips what is drawn in it to), its tick
    and axis labels (which a constrained layout leaves out of account in 3D) within as
    much of the axes' height and of the width the axes was given; whether the zoom
    changed noticeably. ``ax`` must have been laid out (:func:`lay_out`) or drawn."""
    renderer = ax.figure.canvas.get_renderer()
    corners = box_corners(ax)
    low, high = corners.min(axis=0), corners.max(axis=0)
    texts = [text for axis in _axes_axes(ax) for text in [*tick_labels(axis), axis.label]
             if text.get_text()]
    labels = Bbox.union([Bbox([low, high]), *(text.get_window_extent(renderer)
                                              for text in texts)])
    square = ax.bbox
    given = ax.get_position(original=True).transformed(ax.figure.transFigure)
    centre = np.array([square.x0 + square.x1, square.y0 + square.y1]) / 2
    # Per side (left, bottom, right, top): the room from the centre, the box's reach
    # from it (which scales with the zoom) and the labels' reach beyond the box (which
    # does not).
    box_room = BOX_FILL * np.tile([square.width / 2, square.height / 2], 2)
    label_room = BOX_FILL * np.array([centre[0] - given.x0, square.height / 2,
                                      given.x1 - centre[0], square.height / 2])
    reach = np.maximum(np.concatenate([centre - low, high - centre]), 1e-9)
    beyond = np.concatenate([low - labels.p0, labels.p1 - high])
    scale = float(min(np.min(box_room / reach), np.min((label_room - beyond) / reach)))
    if abs(scale - 1.0) < ZOOM_TOLERANCE:
        return False
    aspect = tuple(ax.get_box_aspect())  # (matplotlib scales an array given in place)
    ax.set_box_aspect(aspect)  # zoom 1: what matplotlib scales a zoom of 1 to
    zoom = np.linalg.norm(aspect) / np.linalg.norm(ax.get_box_aspect())
    ax.set_box_aspect(aspect, zoom=zoom * max(scale, 0.1))
    return True


def _owner(fig: Figure, text: Text) -> tuple[Axis, bool]:
    """The axis ``text`` belongs to, and whether it is that axis' label (else a tick
    label)."""
    for ax in fig.axes:
        for axis in _axes_axes(ax):
            if text is axis.label:
                return axis, True
            if text in tick_labels(axis):
                return axis, False
    raise ValueError(f"{text!r} is no label of the figure")


def _thin(axis: Axis) -> None:
    """Ask ``axis`` for about half as many ticks (at least one)."""
    shown = [location for location, _ in ticks_shown(axis)]
    if len(shown) > 2:
        axis.set_major_locator(MaxNLocator(nbins=max(1, (len(shown) - 1) // 2),
                                           steps=NICE_STEPS))
    elif shown:  # two labels that still collide: keep the one nearer the middle
        middle = sum(axis.get_view_interval()) / 2
        axis.set_major_locator(FixedLocator([min(shown, key=lambda x: abs(x - middle))]))


def _overlap(first: Text, second: Text) -> float:
    """How far apart, points, two overlapping labels must move to clear each other with
    :data:`LABEL_GAP` between them: the thinner side of their overlap."""
    renderer = first.figure.canvas.get_renderer()
    a, b = _box(first, renderer), _box(second, renderer)
    width = min(a.x1, b.x1) - max(a.x0, b.x0)
    height = min(a.y1, b.y1) - max(a.y0, b.y0)
    return max(min(width, height), 0.0) * 72.0 / first.figure.dpi + LABEL_GAP


def _rearrange(fig: Figure, pairs: list[tuple[Text, Text]], moves: dict[Axis, float]) -> None:
    """One round of moving labels apart: tick labels of one axis that collide make it
    thin its ticks; a tick label on another axis' label, or (in 3D, at the box's
    corners) on another axis' tick label, is left out (from the axis with more of
    them); an axis label on its own axis' tick labels or on another axis label moves
    away from its axis, as far as they overlap or twice as far as its last move
    (``moves``, points, by axis; updated): a 3D axis label moves along the box's
    diagonal, by less than its pad."""
    crowded: set[Axis] = set()
    moved: dict[Axis, float] = {}
    dropped: dict[Axis, set[Text]] = {}
    for pair in pairs:
        owners = [_owner(fig, text) for text in pair]
        (first, first_is_name), (second, second_is_name) = owners
        if (first_is_name and (second_is_name or first is second)) or (
                second_is_name and first is second):
            axis = first if first_is_name else second
            moved[axis] = max(moved.get(axis, 0.0), _overlap(*pair))
        elif first is second:
            crowded.add(first)
        else:
            axis, text = max(((axis, text) for (axis, is_name), text in
                              zip(owners, pair, strict=True) if not is_name),
                             key=lambda item: len(tick_labels(item[0])))
            dropped.setdefault(axis, set()).add(text)
    for axis in crowded:
        _thin(axis)
    for axis, texts in dropped.items():
        kept = [location for location, text in ticks_shown(axis) if text not in texts]
        if axis not in crowded and kept:
            axis.set_major_locator(FixedLocator(kept))
    for axis, distance in moved.items():
        moves[axis] = max(distance, 2.0 * moves.get(axis, 0.0))
        axis.labelpad += moves[axis]


def _positions(fig: Figure) -> np.ndarray:
    """(A, 4) where ``fig``'s axes are drawn, pixels: left, bottom, width, height."""
    return np.array([ax.bbox.bounds for ax in fig.axes])


@contextmanager
def _layout_only(fig: Figure) -> Iterator[None]:
    """Hide the data of ``fig``'s axes (lines, collections, patches, images) for a while:
    they do not move labels, and measuring them would slow every round of the layout."""
    data = [artist for ax in fig.axes
            for artist in (*ax.lines, *ax.collections, *ax.patches, *ax.images)
            if artist.get_visible()]
    for artist in data:
        artist.set_visible(False)
    try:
        yield
    finally:
        for artist in data:
            artist.set_visible(True)


def lay_out(fig: Figure) -> None:
    """Place everything of ``fig`` where drawing it would, without drawing it: its layout
    engine sizes and places the axes (measuring them: a 3D axes at its box's present
    zoom), then each axes keeps its aspect in that place and places its ticks, tick
    labels and axis labels there."""
    renderer = fig.canvas.get_renderer()
    for ax in fig.axes:
        if isinstance(ax, Axes3D):  # the projection a draw would use (its zoom may be new)
            ax.M = ax.get_proj()
            ax.invM = np.linalg.inv(ax.M)
    engine = fig.get_layout_engine()
    if engine is not None:
        engine.execute(fig)
    for ax in fig.axes:
        ax.apply_aspect()
        for axis in _axes_axes(ax):
            axis.get_tightbbox(renderer)


def _fix_layout(fig: Figure) -> None:
    """Keep ``fig``'s layout as it is: drop its layout engine, so that saving draws it
    once, as laid out (with the engine, or with the placeholder that
    ``set_layout_engine("none")`` leaves, ``savefig`` lays it out and draws it twice)."""
    with rc_context({"figure.autolayout": False, "figure.constrained_layout.use": False}):
        fig.set_layout_engine(None)


def finish(fig: Figure) -> Figure:
    """Fit every 3D box of ``fig`` to its axes and rearrange the labels until none
    overlaps another (see :func:`collisions`); returns ``fig``, laid out for good. Call it
    last, when everything is drawn.

    Round by round, ``fig`` is laid out (:func:`lay_out`, without its data) until its 3D
    boxes fit, no labels collide, and its layout has settled (a 3D axes' labels move
    with the place the layout gives it, so its layout lags a round behind). Nothing is
    drawn: the figure is drawn once, when it is saved."""
    three_d = [ax for ax in fig.axes if isinstance(ax, Axes3D)]
    with _layout_only(fig):
        before = None
        moves: dict[Axis, float] = {}
        for _ in range(MAX_ROUNDS):
            lay_out(fig)
            now = _positions(fig)
            settled = not three_d or (
                before is not None and np.allclose(now, before, atol=LAYOUT_TOLERANCE))
            before = now
            if any([_fit_box(ax) for ax in three_d]):
                continue
            pairs = collisions(fig)
            if pairs:
                _rearrange(fig, pairs, moves)
            elif settled:
                break
    _fix_layout(fig)
    return fig
