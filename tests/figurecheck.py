"""Checks of a drawn figure that a reader would make: legends off the data, no label on
another label, the path outlined. Measured on the figure as drawn (window extents in
pixels), independently of how quadnav lays figures out."""

from __future__ import annotations

from itertools import combinations

from matplotlib.colors import to_rgba
from matplotlib.figure import Figure
from matplotlib.lines import Line2D
from matplotlib.patheffects import Stroke
from mpl_toolkits.mplot3d import Axes3D


class DrawCounter:
    """How many times each figure made while it watches (from ``__init__`` on, through
    ``monkeypatch``) is drawn, as matplotlib itself tells: a figure sends 'draw_event' at
    the end of every draw, rendered or not (a layout's ``draw_without_rendering``, the
    draw ``savefig`` makes before it renders)."""

    def __init__(self, monkeypatch) -> None:
        self.figures: list[Figure] = []
        self.draws: list[int] = []
        make = Figure.__init__

        def watched(fig: Figure, *args, **kwargs) -> None:
            make(fig, *args, **kwargs)
            index = len(self.figures)
            self.figures.append(fig)
            self.draws.append(0)
            fig.canvas.mpl_connect("draw_event", lambda event: self._drawn(index))

        monkeypatch.setattr(Figure, "__init__", watched)

    def _drawn(self, index: int) -> None:
        self.draws[index] += 1

    def of_figures(self) -> list[int]:
        """The draws of each figure with axes, in the order they were made (a figure
        without axes is made only to ask matplotlib something)."""
        return [draws for fig, draws in zip(self.figures, self.draws, strict=True) if fig.axes]


def draw(fig: Figure):
    """Draw ``fig`` as savefig would; returns the renderer."""
    fig.canvas.draw()
    return fig.canvas.get_renderer()


def legends(fig: Figure) -> list:
    """Every legend of ``fig``: the figure's and the axes'."""
    return [*fig.legends, *(ax.get_legend() for ax in fig.axes if ax.get_legend())]


def assert_legends_outside(fig: Figure) -> None:
    """``fig`` has a legend, and every legend lies inside the figure, off every axes'
    area (a 2D axes' data area, a 3D axes' square) and off every title."""
    renderer = draw(fig)
    found = legends(fig)
    assert found, "no legend"
    titles = [ax.title for ax in fig.axes] + ([fig._suptitle] if fig._suptitle else [])
    for legend in found:
        box = legend.get_window_extent(renderer)
        assert fig.bbox.padded(1).contains(box.x0, box.y0), (box, fig.bbox)
        assert fig.bbox.padded(1).contains(box.x1, box.y1), (box, fig.bbox)
        for ax in fig.axes:
            assert not box.overlaps(ax.bbox), (ax, box, ax.bbox)
        for title in titles:
            if title.get_text():
                assert not box.overlaps(title.get_window_extent(renderer)), title.get_text()


def axis_texts(ax) -> dict[str, list]:
    """The drawn tick labels (of ticks inside the view) and the label of each axis of
    ``ax``, by axis name."""
    axes = [ax.xaxis, ax.yaxis] + ([ax.zaxis] if isinstance(ax, Axes3D) else [])
    texts = {}
    for axis in axes:
        low, high = sorted(axis.get_view_interval())
        locations = axis.get_majorticklocs()
        ticks = axis.get_major_ticks(len(locations))
        texts[axis.axis_name] = [
            label for location, tick in zip(locations, ticks, strict=True)
            if low - 1e-9 <= location <= high + 1e-9
            for label in (tick.label1, tick.label2)
            if label.get_visible() and label.get_text()] + [axis.label]
    return texts


def assert_labels_apart(fig: Figure, min_ticks: int = 2) -> None:
    """No tick label or axis label of an axes of ``fig`` overlaps another, every label
    lies inside the figure, and each labelled axis keeps at least ``min_ticks`` tick
    labels."""
    renderer = draw(fig)
    for ax in fig.axes:
        texts = axis_texts(ax)
        for name, labels in texts.items():
            if labels[-1].get_text():
                assert len(labels) - 1 >= min_ticks, (ax, name, [t.get_text() for t in labels])
        boxes = [(text.get_text(), text.get_window_extent(renderer))
                 for labels in texts.values() for text in labels if text.get_text()]
        for (first, a), (second, b) in combinations(boxes, 2):
            assert not a.overlaps(b), (ax.get_title(), first, second, a, b)
        for text, box in boxes:
            assert fig.bbox.padded(1).contains(box.x0, box.y0), (text, box)
            assert fig.bbox.padded(1).contains(box.x1, box.y1), (text, box)


def assert_outlined(line: Line2D) -> None:
    """``line`` is drawn over a white and a black edge, both wider than itself, so it
    shows on blocks of any colour."""
    strokes = [effect for effect in line.get_path_effects() if isinstance(effect, Stroke)]
    edges = {to_rgba(stroke._gc["foreground"])[:3]: stroke._gc["linewidth"]
             for stroke in strokes}
    assert set(edges) == {(0.0, 0.0, 0.0), (1.0, 1.0, 1.0)}, edges
    assert edges[(0.0, 0.0, 0.0)] > edges[(1.0, 1.0, 1.0)] > line.get_linewidth()


def assert_texts_off_other_axes(fig: Figure) -> None:
    """No tick label or title of an axes of ``fig`` reaches into another visible axes (a
    neighbouring panel, a colour bar), and the texts drawn inside each axes (a heat map's
    cells) lie inside it, apart from one another."""
    renderer = draw(fig)
    shown = [ax for ax in fig.axes if ax.get_visible()]
    for ax in shown:
        texts = [text for labels in axis_texts(ax).values() for text in labels
                 if text.get_text()] + ([ax.title] if ax.get_title() else [])
        for text in texts:
            box = text.get_window_extent(renderer)
            for other in shown:
                assert other is ax or not box.overlaps(other.bbox), (text.get_text(), other)
        inside = [(text.get_text(), text.get_window_extent(renderer)) for text in ax.texts]
        for name, box in inside:
            assert ax.bbox.padded(1).contains(box.x0, box.y0), (name, box, ax.bbox)
            assert ax.bbox.padded(1).contains(box.x1, box.y1), (name, box, ax.bbox)
        for (first, a), (second, b) in combinations(inside, 2):
            assert not a.overlaps(b), (first, second)
