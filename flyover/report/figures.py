"""The report's own figures (matplotlib, PNG, byte-reproducible).

The throughput figures (paper Fig. 4–6) are the workflow's (``results/figures/``);
these are the ones no stage draws:

* :func:`plot_fuel_grid` — paper Table IV as a heatmap: mean fuel (ml/km) of the
  ramps by target radius and slope, a panel per direction (up, down);
* :func:`plot_fuel_by_class` — paper Fig. 7: the distribution of fuel (ml/km) per
  class, up and down ramps side by side;
* :func:`plot_class_geometry` — one class's ramps: achieved against target radius and
  slope, and the ramp lengths.
"""

from __future__ import annotations

import io
import math
import os
from collections import defaultdict
from typing import Mapping, Sequence

from flyover.topology.io import atomic_write

__all__ = ["plot_fuel_grid", "plot_fuel_by_class", "plot_class_geometry"]


def _pyplot():
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    return plt


def _save(fig, path: str | os.PathLike) -> None:
    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=110, metadata={"Software": None})
    _pyplot().close(fig)
    atomic_write(path, buf.getvalue())


def _radius_label(r: float) -> str:
    return "∞" if not math.isfinite(r) else f"{r:g}"


def plot_fuel_grid(rows: Sequence[Mapping], path: str | os.PathLike) -> None:
    """Table IV heatmap from the rows of the named query ``fuel-grid``
    (``radius_m, slope_pct, direction, mean_ml_per_km``)."""
    plt = _pyplot()
    directions = [d for d in ("up", "down") if any(r["direction"] == d for r in rows)]
    radii = sorted({r["radius_m"] for r in rows}, key=lambda r: (not math.isfinite(r), r))
    slopes = sorted({r["slope_pct"] for r in rows})
    fig, axes = plt.subplots(1, max(1, len(directions)), squeeze=False,
                             figsize=(1.2 + 0.75 * max(3, len(slopes)) * max(1, len(directions)),
                                      1.4 + 0.42 * max(3, len(radii))))
    values = [r["mean_ml_per_km"] for r in rows if r["mean_ml_per_km"] is not None]
    vmin, vmax = (min(values), max(values)) if values else (0.0, 1.0)
    image = None
    for ax, d in zip(axes[0], directions):
        grid = [[math.nan] * len(slopes) for _ in radii]
        for r in rows:
            if r["direction"] == d and r["mean_ml_per_km"] is not None:
                grid[radii.index(r["radius_m"])][slopes.index(r["slope_pct"])] = r["mean_ml_per_km"]
        image = ax.imshow(grid, cmap="magma_r", vmin=vmin, vmax=vmax, aspect="auto")
        for i, line in enumerate(grid):
            for j, v in enumerate(line):
                if not math.isnan(v):
                    dark = (v - vmin) / max(vmax - vmin, 1e-9) > 0.55
                    ax.text(j, i, f"{v:.0f}", ha="center", va="center", fontsize=7,
                            color="white" if dark else "black")
        ax.set_xticks(range(len(slopes)), [f"{s:g}" for s in slopes])
        ax.set_yticks(range(len(radii)), [_radius_label(r) for r in radii])
        ax.set_xlabel("target slope (%)")
        ax.set_ylabel("target radius (m)")
        ax.set_title(f"{d} ramps: mean fuel (ml/km)", fontsize=9)
    if image is not None:
        fig.colorbar(image, ax=list(axes[0]), shrink=0.8, label="ml/km")
    _save(fig, path)


def plot_fuel_by_class(rows: Sequence[Mapping], names: Mapping[str, str],
                       path: str | os.PathLike) -> None:
    """Fig. 7: fuel (ml/km) of every completed ramp, per class and direction
    (``rows``: ``class_id, direction, fuel_ml_per_km``)."""
    plt = _pyplot()
    per: dict[tuple[str, str], list[float]] = defaultdict(list)
    for r in rows:
        if r["fuel_ml_per_km"] is not None and math.isfinite(r["fuel_ml_per_km"]):
            per[(r["class_id"], r["direction"])].append(float(r["fuel_ml_per_km"]))
    classes = sorted({c for c, _ in per}, key=lambda c: names.get(c, c))
    fig, ax = plt.subplots(figsize=(max(5.0, 1.1 * len(classes) + 1.5), 3.8))
    colours = {"up": "#c0392b", "down": "#2471a3", "level": "#7f8c8d"}
    offsets = {"up": -0.25, "level": 0.0, "down": 0.25}
    for d in ("up", "level", "down"):
        data = [(i + offsets[d], per[(c, d)]) for i, c in enumerate(classes) if per.get((c, d))]
        if not data:
            continue
        bp = ax.boxplot([v for _, v in data], positions=[p for p, _ in data], widths=0.22,
                        patch_artist=True, showfliers=True, flierprops={"markersize": 2})
        for box in bp["boxes"]:
            box.set(facecolor=colours[d], alpha=0.55)
        ax.plot([], [], "s", color=colours[d], alpha=0.55, label=d)
    ax.set_xticks(range(len(classes)), [names.get(c, c) for c in classes], rotation=30,
                  ha="right", fontsize=8)
    ax.set_ylabel("truck fuel (ml/km)")
    ax.set_title("fuel per ramp by class and direction (paper Fig. 7)", fontsize=9)
    ax.legend(fontsize=8, frameon=False)
    ax.grid(axis="y", alpha=0.3)
    fig.tight_layout()
    _save(fig, path)


def plot_class_geometry(rows: Sequence[Mapping], path: str | os.PathLike, *,
                        title: str = "") -> None:
    """One class's built ramps (rows of ``geometry``): achieved minimum radius against
    the target (a straight ramp's target ∞ drawn at the right), achieved maximum
    slope against the target, and ramp lengths."""
    plt = _pyplot()
    fig, (a, b, c) = plt.subplots(1, 3, figsize=(10.5, 3.2))
    rows = sorted(rows, key=lambda r: bool(r["ok"]), reverse=True)  # missed ones on top
    finite = [r["target_radius_m"] for r in rows if math.isfinite(r["target_radius_m"])]
    inf_x = 1.25 * max(finite) if finite else 100.0
    colour = ["#2e86c1" if r["ok"] else "#c0392b" for r in rows]
    xr = [r["target_radius_m"] if math.isfinite(r["target_radius_m"]) else inf_x for r in rows]
    yr = [min(r["min_radius_m"], 4 * inf_x) for r in rows]
    a.scatter(xr, yr, s=9, c=colour, alpha=0.7)
    lim = max(finite + [10.0]) * 1.05
    lo = 0.8 * min(finite + [lim])
    diagonal = [lo + (lim - lo) * i / 100 for i in range(101)]  # y = x: a curve on a log axis
    a.plot(diagonal, diagonal, color="0.5", lw=0.8)
    a.axvline(inf_x, color="0.85", lw=0.8)
    a.text(inf_x, 0.02, " target ∞", transform=a.get_xaxis_transform(), fontsize=7, color="0.4")
    a.set_xlabel("target radius (m)")
    a.set_ylabel("achieved min radius (m)")
    a.set_yscale("log")
    b.scatter([r["target_slope_pct"] for r in rows], [r["max_slope_pct"] for r in rows], s=9,
              c=colour, alpha=0.7)
    top = max([r["target_slope_pct"] for r in rows] + [1.0]) * 1.1
    b.plot([0, top], [0, top], color="0.5", lw=0.8)
    b.set_xlabel("target slope (%)")
    b.set_ylabel("achieved max slope (%)")
    lengths = [r["length_m"] for r in rows if math.isfinite(r["length_m"])]
    c.hist(lengths, bins=20, color="#5d6d7e")
    c.set_xlabel("ramp length (m)")
    c.set_ylabel("ramps")
    fig.suptitle(title + "  (blue: within tolerance, red: missed)", fontsize=9)
    fig.tight_layout()
    _save(fig, path)
