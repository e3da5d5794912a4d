"""The run's map as a PNG: metres east/north of the map's origin (geojson.map_origin), equal scale, a scale bar."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from companion.fence_from_profile import fence_for
from mdm_ground.run_map.geojson import map_origin
from mdm_ground.run_map.tracks import VehicleTrack
from mdm_profiles import MissionProfile


def scale_bar_length(span: float) -> float:
    """A round length (1, 2 or 5 x 10^k m) of about a fifth of ``span`` metres."""
    target = span / 5.0
    power = 10.0 ** math.floor(math.log10(target))
    return max(m * power for m in (1.0, 2.0, 5.0) if m * power <= target)


def _label(metres: float) -> str:
    return f"{metres / 1000:g} km" if metres >= 1000 else f"{metres:g} m"


def draw_png(profile: MissionProfile, tracks: list[VehicleTrack], path: Path, title: str) -> None:
    """Draw the fence, search area, targets, paths (a lawnmower's planned lanes dotted),
    detections and confirmations to ``path``."""
    import matplotlib

    matplotlib.use("Agg")  # no display on a companion computer or in CI
    import matplotlib.pyplot as plt
    from matplotlib.patches import Circle, Polygon
    from mpl_toolkits.axes_grid1.anchored_artists import AnchoredSizeBar

    a = profile.area
    # The map's own aspect plus room for the legend on the right (no empty bands).
    height = min(9.0, max(3.5, 7.0 * a.north / a.east))
    fig, ax = plt.subplots(figsize=(10.5, height + 1.3), dpi=110)
    fence = fence_for(profile).vertices
    ax.add_patch(
        Polygon(
            np.c_[[0, 0, a.east, a.east], [0, a.north, a.north, 0]],
            closed=True,
            fill=True,
            facecolor="0.95",
            edgecolor="0.6",
            lw=1.0,
            label="search area",
        )
    )
    ax.add_patch(
        Polygon(
            fence[:, ::-1],
            closed=True,
            fill=False,
            edgecolor="black",
            lw=1.6,
            ls="--",
            label="fence",
        )
    )
    radius = profile.sensors[-1].radius
    for t in profile.targets:
        colour = "0.45" if t.false_target else "purple"  # not in the vehicles' colour cycle
        ax.add_patch(Circle((t.east, t.north), radius, fill=False, edgecolor=colour, lw=0.8))
        ax.plot(t.east, t.north, "x" if t.false_target else "o", color=colour, ms=7, mew=2)
    ax.plot([], [], "o", color="purple", label=f"target (circle: {_label(radius)} confirmation)")
    if any(t.false_target for t in profile.targets):
        ax.plot([], [], "x", color="0.45", mew=2, label="false target")
    cycle = plt.rcParams["axes.prop_cycle"].by_key()["color"]
    for track in tracks:
        colour = cycle[track.vehicle % len(cycle)]
        for lane_a, lane_b in zip(track.lanes[::2], track.lanes[1::2], strict=False):
            ax.plot([lane_a[1], lane_b[1]], [lane_a[0], lane_b[0]], ":", color=colour, lw=0.9)
        if track.path:
            east = [s.east for s in track.path]
            north = [s.north for s in track.path]
            ax.plot(east, north, "-", color=colour, lw=1.4, label=f"vehicle {track.vehicle}")
            ax.plot(east[0], north[0], "s", color=colour, ms=6)
        for s, _ in track.detections:
            ax.plot(s.east, s.north, "^", color=colour, ms=7, mec="black", mew=0.5)
        for s in track.confirmations:
            ax.plot(s.east, s.north, "*", color="gold", ms=18, mec="black", mew=1.0)
    if any(track.lanes for track in tracks):
        ax.plot([], [], ":", color="0.3", lw=0.9, label="planned lanes (lawnmower)")
    ax.plot([], [], "s", color="0.3", label="path start")
    ax.plot([], [], "^", color="0.3", mec="black", mew=0.5, label="detection (level up)")
    ax.plot([], [], "*", color="gold", ms=14, mec="black", label="confirmation")
    ax.set_aspect("equal")
    ax.autoscale_view()
    x0, x1 = ax.get_xlim()
    y0, y1 = ax.get_ylim()
    pad = 0.05 * max(x1 - x0, y1 - y0)
    ax.set_xlim(x0 - pad, x1 + pad)
    ax.set_ylim(y0 - pad, y1 + pad)
    bar = scale_bar_length(x1 - x0 + 2 * pad)
    ax.add_artist(
        AnchoredSizeBar(
            ax.transData,
            bar,
            _label(bar),
            loc="lower right",
            pad=0.6,
            sep=4,
            size_vertical=(y1 - y0) * 0.006,
            frameon=True,
        )
    )
    ax.annotate(
        "N",
        xy=(0.04, 0.95),
        xytext=(0.04, 0.85),
        xycoords="axes fraction",
        ha="center",
        fontsize=12,
        fontweight="bold",
        arrowprops={"arrowstyle": "-|>", "color": "black"},
    )
    lat, lon = map_origin(profile, tracks)
    ax.set_xlabel(f"east of the origin ({lat:.6f}, {lon:.6f}), m")
    ax.set_ylabel("north of the origin, m")
    ax.set_title(title)
    ax.grid(True, color="0.85", lw=0.5)
    ax.legend(loc="upper left", bbox_to_anchor=(1.01, 1.0), fontsize=9, framealpha=0.9)
    fig.savefig(path, bbox_inches="tight")  # the legend outside the axes included
    plt.close(fig)
