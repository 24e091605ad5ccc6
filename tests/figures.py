"""Shared by the figure tests: a written figure file holds the drawn figure, and the
artists of a figure read back as data."""

from __future__ import annotations

import numpy as np

DPI = 120          # emaphm.plots.save_figure's default


def assert_png_of(path, size_in, dpi: int = DPI) -> None:
    """``path`` is a PNG of a figure of ``size_in`` (width, height) inches at ``dpi`` (or of
    that ``Figure``) as :func:`emaphm.plots.save_figure` writes it: it decodes, has the
    figure's size in pixels, and is drawn (hundreds of colours, not a blank canvas)."""
    from matplotlib.image import imread

    if hasattr(size_in, "get_size_inches"):
        size_in = size_in.get_size_inches()
    img = imread(path)                                  # raises on anything but an image
    w, h = (round(float(x) * dpi) for x in size_in)
    assert img.shape[:2] == (h, w), (img.shape, (h, w))
    colours = np.unique(img.reshape(-1, img.shape[2]), axis=0)
    assert len(colours) > 100, f"{path}: {len(colours)} colours, a blank figure?"


def legend_texts(ax) -> list[str]:
    legend = ax.get_legend()
    return [] if legend is None else [t.get_text() for t in legend.get_texts()]


def markers(ax, marker: str) -> list:
    """The lines of ``ax`` drawn with ``marker`` and no connecting line."""
    return [ln for ln in ax.lines if ln.get_marker() == marker and ln.get_linestyle() == "None"]
