"""``plan.png``: the plan view of an OpenDRIVE network, lanes coloured by height.

In the spirit of the paper's interchange diagrams (Fig. 5d–f): every driving
lane is filled with the colour of its height (higher roads drawn on top, so
flyovers read at a glance), shoulders in grey, each topology element named
at its middle.
"""

from __future__ import annotations

import os

import numpy as np

from flyover.opendrive.reader import XodrNetwork, XodrRoad, _piecewise

__all__ = ["lane_polygons", "draw_plan"]


def lane_polygons(road: XodrRoad, step_m: float = 4.0, chunk: int = 10
                  ) -> list[tuple[str, np.ndarray, float]]:
    """(lane type, polygon (n×2), mean height) chunks of every lane of ``road``, ``chunk``
    steps long (short enough for a climbing ramp to be drawn over what it crosses)."""
    out = []
    bounds = [sec.s for sec in road.sections] + [road.length]
    for sec, s1 in zip(road.sections, bounds[1:]):
        if s1 - sec.s < 1e-6:
            continue
        n = max(2, int(np.ceil((s1 - sec.s) / step_m)) + 1)
        s = np.linspace(sec.s, s1, n)
        x, y, z, h = road.reference(s)
        nx, ny = -np.sin(h), np.cos(h)
        for side in (-1, 1):
            t = _piecewise(road.lane_offset, s)
            k = 1
            while side * k in sec.lanes:
                lane = sec.lanes[side * k]
                w = lane.width(s - sec.s)
                t_out = t + side * w
                if np.any(w > 1e-3):
                    for a in range(0, n - 1, chunk):
                        b = min(a + chunk + 1, n)
                        poly = np.concatenate([
                            np.stack([x[a:b] + nx[a:b] * t[a:b], y[a:b] + ny[a:b] * t[a:b]], 1),
                            np.stack([x[a:b] + nx[a:b] * t_out[a:b], y[a:b] + ny[a:b] * t_out[a:b]], 1)[::-1]])
                        out.append((lane.type, poly, float(z[a:b].mean())))
                t = t_out
                k += 1
    return out


def draw_plan(net: XodrNetwork, path: str | os.PathLike, title: str | None = None) -> None:
    """Draw ``net`` to a PNG at ``path`` (byte-reproducible)."""
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415
    from matplotlib.collections import PolyCollection  # noqa: PLC0415

    from flyover.topology.io import atomic_write  # noqa: PLC0415

    chunks = [c for r in net.roads.values() for c in lane_polygons(r)]
    fig, ax = plt.subplots(figsize=(8, 8), dpi=110)
    zs = np.array([c[2] for c in chunks]) if chunks else np.zeros(1)
    vmin, vmax = float(zs.min()), float(max(zs.max(), zs.min() + 1.0))
    order = sorted(range(len(chunks)), key=lambda i: (chunks[i][2], chunks[i][0] != "shoulder"))
    polys = [chunks[i][1] for i in order]
    drive = np.array([chunks[i][0] != "shoulder" for i in order], dtype=bool)
    cmap = plt.get_cmap("viridis")
    norm = plt.Normalize(vmin, vmax)
    heights = np.array([chunks[i][2] for i in order], dtype=float).reshape(-1)
    colors = cmap(norm(heights)) if len(order) else np.zeros((0, 4))  # one call, not one per chunk
    colors[~drive] = (0.72, 0.72, 0.72, 1.0)
    ax.add_collection(PolyCollection(polys, facecolors=colors, edgecolors=colors, linewidths=0.3))
    named: dict[str, list[XodrRoad]] = {}
    for r in net.roads.values():
        named.setdefault(r.name or r.id, []).append(r)
    for name, roads in sorted(named.items()):
        # label each element at the middle of its piece farthest from the origin (the centre)
        # a carriageway at its entry (so opposite carriageways part), else the middle of
        # the element's piece farthest from the origin (the interchange centre)
        entry = [r for r in roads if r.junction == "-1" and r.predecessor is None
                 and r.geometry[0].kind == "line"]
        if entry:
            x, y, _, _ = entry[0].reference(min(80.0, entry[0].length / 2))
        else:
            mids = [(r, r.reference(r.length / 2)) for r in roads if r.junction == "-1"] or \
                [(r, r.reference(r.length / 2)) for r in roads]
            _, (x, y, _, _) = max(mids, key=lambda m: (float(m[1][0][0]) ** 2
                                                     + float(m[1][1][0]) ** 2, m[0].length))
        ax.annotate(name, (float(x[0]), float(y[0])), fontsize=8, ha="center", va="center",
                    bbox=dict(boxstyle="round,pad=0.15", fc="white", ec="0.5", lw=0.5, alpha=0.85))
    if polys:
        allp = np.concatenate(polys)
        pad = 20.0
        ax.set_xlim(allp[:, 0].min() - pad, allp[:, 0].max() + pad)
        ax.set_ylim(allp[:, 1].min() - pad, allp[:, 1].max() + pad)
    ax.set_aspect("equal")
    ax.set_xlabel("x (m, east)")
    ax.set_ylabel("y (m, north)")
    ax.set_title(title or (net.header.get("name") or "interchange"), fontsize=10)
    sm = plt.cm.ScalarMappable(norm=norm, cmap=cmap)
    fig.colorbar(sm, ax=ax, shrink=0.7, label="height z (m)")
    fig.subplots_adjust(left=0.1, right=0.98, bottom=0.07, top=0.95)  # fixed: tight_layout drew the figure twice
    import io  # noqa: PLC0415

    buf = io.BytesIO()
    fig.savefig(buf, format="png", metadata={"Software": None})
    plt.close(fig)
    atomic_write(path, buf.getvalue())
