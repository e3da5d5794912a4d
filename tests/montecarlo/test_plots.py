"""The report's box plots: the legend left out of the tight layout changes no layout."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest

from mdm_montecarlo.study.plots import _boxes


def _layout(in_layout: bool, data: list[list[float]]) -> tuple[tuple[float, ...], bool]:
    """The tight layout's subplot parameters of a box plot as the report draws it, with its
    legend in or out of the layout, and whether the drawn legend lies inside its axes."""
    fig, ax = plt.subplots(figsize=(6.0, 4.0))
    labels = [f"method {k}\n(variant)" for k in range(len(data))]
    _boxes(ax, data, labels, "search method", "targets confirmed T_nc", [4.3, None, 9.1])
    legend = ax.get_legend()
    assert legend is not None
    assert not legend.get_in_layout()  # as _boxes leaves it
    legend.set_in_layout(in_layout)
    fig.tight_layout()
    fig.canvas.draw()
    p = fig.subplotpars
    frame = ax.get_window_extent()
    box = legend.get_window_extent()
    inside = frame.x0 <= box.x0 and box.x1 <= frame.x1 and frame.y0 <= box.y0 and box.y1 <= frame.y1
    plt.close(fig)
    return (p.left, p.right, p.bottom, p.top, p.wspace, p.hspace), inside


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_best_legend_lies_inside_its_axes_so_the_layout_is_the_same_without_it(
    seed: int,
) -> None:
    rng = np.random.default_rng(seed)
    data = [list(rng.integers(0, 11, 300).astype(float)) for _ in range(3)]
    with_legend, inside = _layout(True, data)
    without, _ = _layout(False, data)
    assert inside
    assert without == with_legend
