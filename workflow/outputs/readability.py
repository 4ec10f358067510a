"""What makes a figure hard to read, found from matplotlib's own text extents: labels that
overlap, tick labels in offset or power notation, and panels that show nothing and say
nothing. :func:`workflow.outputs.figures.save` logs every problem found, so that a figure a
reader cannot take in at a glance is named in its rule's log.
"""

from __future__ import annotations

import itertools

import matplotlib.pyplot as plt
import numpy as np
from matplotlib.axis import Axis
from matplotlib.backend_bases import RendererBase
from matplotlib.text import Text
from matplotlib.transforms import Bbox

__all__ = [
    "OVERLAP_TOLERANCE_PX",
    "drawn_texts",
    "overlapping_texts",
    "notation_problems",
    "reaches_past_edge",
    "readability_problems",
]


OVERLAP_TOLERANCE_PX = 1.0
"""Extents are shrunk by this much before comparing: glyph boxes that only touch are
legible (matplotlib pads each box by a fraction of a pixel)."""


def _drawn_tick_labels(axis: Axis) -> list[Text]:
    """Tick labels matplotlib draws: visible, not empty, at a tick inside the view."""
    low, high = sorted(axis.get_view_interval())
    span = high - low
    labels = []
    for tick in [*axis.get_major_ticks(), *axis.get_minor_ticks()]:
        location = tick.get_loc()
        if location is None or not low - 1e-9 * span <= location <= high + 1e-9 * span:
            continue
        for label in (tick.label1, tick.label2):
            if label.get_visible() and label.get_text().strip():
                labels.append(label)
    return labels


def drawn_texts(figure: plt.Figure) -> list[Text]:
    """Every text artist the figure draws (titles, labels, tick labels, legends, notes)."""
    tick_labels, hidden = [], set()
    for axes in figure.axes:
        for axis in (axes.xaxis, axes.yaxis):
            for tick in [*axis.get_major_ticks(), *axis.get_minor_ticks()]:
                hidden.update({id(tick.label1), id(tick.label2)})
            if axes.axison:
                tick_labels.extend(_drawn_tick_labels(axis))
    others = [
        text
        for text in figure.findobj(Text)
        if id(text) not in hidden
        and text.get_visible()
        and text.get_text().strip()
        and (text.axes is None or text.axes.get_visible())
    ]
    return tick_labels + others


def overlapping_texts(figure: plt.Figure, renderer: RendererBase | None = None) -> list[tuple[str, str]]:
    """Pairs of drawn texts whose extents overlap (text of each pair).

    Text extents need the positions a draw computes, not its pixels. Without
    ``renderer`` the figure is laid out without being rendered; with it, the figure has
    just been drawn by it (:func:`workflow.outputs.figures.save` checks the layout that
    saving the figure makes anyway) and its extents are taken as they are."""
    if renderer is None:
        figure.draw_without_rendering()
        renderer = figure.canvas.get_renderer()
    boxes = []
    for text in drawn_texts(figure):
        extent = text.get_window_extent(renderer)
        if extent.width <= 0 or extent.height <= 0:
            continue
        shrunk = Bbox.from_extents(
            extent.x0 + OVERLAP_TOLERANCE_PX,
            extent.y0 + OVERLAP_TOLERANCE_PX,
            extent.x1 - OVERLAP_TOLERANCE_PX,
            extent.y1 - OVERLAP_TOLERANCE_PX,
        )
        boxes.append((text.get_text(), shrunk))
    return [(a, b) for (a, box_a), (b, box_b) in itertools.combinations(boxes, 2) if box_a.overlaps(box_b)]


def reaches_past_edge(figure: plt.Figure, renderer: RendererBase) -> bool:
    """Whether a drawn text or a legend reaches past the figure's edge, in the draw of
    ``figure`` that ``renderer`` has just made (more than half a pixel out)."""
    edge = figure.bbox
    legends = [legend for legend in (*figure.legends, *(axes.get_legend() for axes in figure.axes)) if legend]
    for artist in (*drawn_texts(figure), *legends):
        extent = artist.get_window_extent(renderer)
        if extent.width <= 0 or extent.height <= 0:
            continue
        if (
            extent.x0 < edge.x0 - 0.5
            or extent.y0 < edge.y0 - 0.5
            or extent.x1 > edge.x1 + 0.5
            or extent.y1 > edge.y1 + 0.5
        ):
            return True
    return False


def _shows_data(axes: plt.Axes) -> bool:
    """Whether a panel draws any data (a line or collection with finite points, a bar, an image)."""
    for line in axes.get_lines():
        data = np.asarray(line.get_xydata(), dtype=float)
        if line.get_visible() and data.size and np.isfinite(data).all(axis=1).any():
            return True
    for collection in axes.collections:
        offsets = np.asarray(collection.get_offsets(), dtype=float)
        if collection.get_visible() and (len(collection.get_paths()) or offsets.size):
            return True
    return bool(axes.patches or axes.images)


def notation_problems(axes: plt.Axes) -> list[str]:
    """Tick labels that are not plain numbers: an offset or multiplier ('+1.233e2',
    '1e-3') or power notation ('10⁰' drawn from mathtext)."""
    problems = []
    for name, axis in (("x", axes.xaxis), ("y", axes.yaxis)):
        offset = axis.get_offset_text().get_text()
        if axes.axison and offset.strip():
            problems.append(f"{name} axis uses offset notation '{offset}'")
        powers = [label.get_text() for label in _drawn_tick_labels(axis) if "$" in label.get_text()]
        if axes.axison and powers:
            problems.append(f"{name} axis has tick labels in power notation {powers[:3]}")
    return problems


def readability_problems(figure: plt.Figure, renderer: RendererBase | None = None) -> list[str]:
    """Everything that keeps a reader from taking the figure in at a glance.

    Parameters
    ----------
    figure : Figure
    renderer : RendererBase, optional
        The renderer of a draw of the figure just made (its layout is checked as it
        is); without it the figure is laid out first (:func:`overlapping_texts`).

    Returns
    -------
    list of str
        One sentence per problem: overlapping texts (quoted), offset or power tick
        notation, and panels that draw no data and carry no note. Empty for a readable
        figure.

    Examples
    --------
    >>> import matplotlib
    >>> matplotlib.use("Agg")
    >>> figure, axis = plt.subplots(figsize=(3, 2))
    >>> _ = axis.plot([0.1, 1.0], [0.002, 0.003])
    >>> _ = axis.text(0.5, 0.5, "damping ratio"), axis.text(0.52, 0.5, "frequency")
    >>> readability_problems(figure)
    ["texts overlap: 'damping ratio' and 'frequency'"]
    >>> plt.close(figure)
    """
    problems = [f"texts overlap: '{a}' and '{b}'" for a, b in overlapping_texts(figure, renderer)]
    for index, axes in enumerate(figure.axes):
        title = axes.get_title() or f"panel {index + 1}"
        problems.extend(f"{title}: {problem}" for problem in notation_problems(axes))
        noted = any(text.get_text().strip() for text in axes.texts)
        if not _shows_data(axes) and not noted:
            problems.append(f"{title}: the panel shows no data and no note says why")
    return problems
