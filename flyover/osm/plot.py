"""Picture of an OSM interchange: geometry coloured by topology node.

Roads are drawn thick, ramps thin, each topology node in its own colour and
named at its middle; every diverge and merge point is marked with its label
(``Out-R``, ``In-M`` ...), so a person can check the extraction at a glance.
"""

from __future__ import annotations

import os

import numpy as np

from flyover.errors import TopologyError
from flyover.topology.model import Kind, Topology

__all__ = ["plot_osm_topology", "has_osm_geometry"]


def has_osm_geometry(topology: Topology) -> bool:
    """True when ``topology`` came from an OSM extract and carries its geometry."""
    return isinstance(topology.attrs.get("osm"), dict) and "lines" in topology.attrs["osm"]


def plot_osm_topology(topology: Topology, path: str | os.PathLike, title: str | None = None) -> None:
    """Draw the OSM geometry of ``topology`` to a PNG at ``path`` (deterministic).

    Raises
    ------
    TopologyError
        ``topology`` carries no OSM geometry.
    """
    if not has_osm_geometry(topology):
        raise TopologyError("no OSM geometry to draw", source=topology.source, element=topology.name)
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    osm = topology.attrs["osm"]
    g = topology.graph
    cmap = plt.get_cmap("tab20")
    fig, ax = plt.subplots(figsize=(9, 9), dpi=110)
    for k, node in enumerate(sorted(osm["lines"])):
        xy = np.asarray(osm["lines"][node], float).reshape(-1, 2)
        is_road = g.nodes[node]["kind"] is Kind.ROAD
        color = "#444444" if is_road else cmap(k % 20)
        if len(xy) > 1:
            ax.plot(xy[:, 0], xy[:, 1], "-", color=color, lw=4.0 if is_road else 2.2,
                    alpha=0.55 if is_road else 0.95, solid_capstyle="round", zorder=1 if is_road else 2)
            mid = len(xy) // 2
            j = min(mid + 1, len(xy) - 1)
            ax.annotate("", xy=xy[j], xytext=xy[mid - 1 if mid == j else mid],
                        arrowprops={"arrowstyle": "-|>", "color": color, "lw": 1.5}, zorder=3)
        else:
            ax.plot(xy[:, 0], xy[:, 1], "o", color=color, zorder=2)
        m = xy[len(xy) // 2]
        attrs = g.nodes[node]
        text = node if is_road else f"{node}\n{attrs.get('length_m', 0):.0f} m, R{attrs.get('min_radius_m', 0):.0f}"
        ax.text(m[0], m[1], text, fontsize=8 if is_road else 7, color="white" if is_road else "black",
                ha="center", va="center", zorder=5,
                bbox={"boxstyle": "round,pad=0.2", "fc": color, "ec": "none", "alpha": 0.85})
    seen: dict[tuple[float, float], int] = {}
    for (x, y), src, dst, label in osm["junctions"]:
        key = (round(x, 1), round(y, 1))
        k = seen.get(key, 0)
        seen[key] = k + 1
        ax.plot([x], [y], "k.", ms=6, zorder=4)
        ax.annotate(f"{src}→{dst} {label}", (x, y), xytext=(6, 6 + 9 * k), textcoords="offset points",
                    fontsize=6.5, zorder=6,
                    bbox={"boxstyle": "round,pad=0.1", "fc": "#fffbe6", "ec": "#bbbbbb", "lw": 0.5})
    lat0, lon0 = osm["origin"]
    ax.set_title(f"{title or topology.name}: {topology.n_roads} roads, {topology.n_ramps} ramps, "
                 f"{topology.shape}\n(metres east/north of {lat0:.5f}, {lon0:.5f}; "
                 "data © OpenStreetMap contributors, ODbL)", fontsize=9)
    ax.set_aspect("equal")
    ax.grid(True, lw=0.3, alpha=0.5)
    ax.tick_params(labelsize=7)
    fig.tight_layout()
    import io

    from flyover.topology.io import atomic_write

    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    plt.close(fig)
    atomic_write(path, buf.getvalue())
