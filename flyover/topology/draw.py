"""Drawing of a topology graph in the style of the paper's Fig. 1b.

Roads are squares, ramps circles; edges are arrows in the direction of
travel, coloured and labelled by their label (Out-R, In-L, ...).
"""

from __future__ import annotations

import os

import networkx as nx

from flyover.topology.model import Kind, Label, Topology

__all__ = ["draw_topology", "LABEL_COLORS"]

LABEL_COLORS = {
    Label.OUT_R: "#1f77b4", Label.OUT_L: "#17becf", Label.OUT_M: "#7f7f7f",
    Label.IN_R: "#d62728", Label.IN_L: "#ff7f0e", Label.IN_M: "#8c564b",
}


def _layout(topology: Topology) -> dict[str, tuple[float, float]]:
    """Roads on an outer ring (grouped by expressway), ramps placed by stress layout."""
    import numpy as np

    g = topology.graph
    roads = [r for roads in topology.expressways.values() for r in roads]
    ring = {r: (np.cos(2 * np.pi * i / len(roads)), np.sin(2 * np.pi * i / len(roads)))
            for i, r in enumerate(roads)}
    init = {**ring}
    ramps = topology.ramps
    for i, r in enumerate(ramps):
        a = 2 * np.pi * (i + 0.5) / max(len(ramps), 1)
        init[r] = (0.5 * np.cos(a), 0.5 * np.sin(a))
    und = nx.Graph(g.to_undirected())
    pos = nx.spring_layout(und, pos=init, fixed=roads, iterations=200, seed=1, k=0.6)
    return {n: (float(x), float(y)) for n, (x, y) in pos.items()}


def draw_topology(topology: Topology, path: str | os.PathLike, title: str | None = None) -> None:
    """Draw ``topology`` to a PNG at ``path`` (deterministic for a given topology)."""
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    from matplotlib.lines import Line2D

    g = topology.graph
    pos = _layout(topology)
    fig, ax = plt.subplots(figsize=(7, 7), dpi=110)
    roads = [n for n in g if g.nodes[n]["kind"] is Kind.ROAD]
    ramps = [n for n in g if g.nodes[n]["kind"] is Kind.RAMP]
    nx.draw_networkx_nodes(g, pos, nodelist=roads, node_shape="s", node_color="#333333",
                           node_size=900, ax=ax)
    nx.draw_networkx_nodes(g, pos, nodelist=ramps, node_shape="o", node_color="#f2f2f2",
                           edgecolors="#333333", node_size=700, ax=ax)
    nx.draw_networkx_labels(g, pos, labels={n: n for n in roads}, font_color="white",
                            font_weight="bold", ax=ax)
    nx.draw_networkx_labels(g, pos, labels={n: n for n in ramps}, ax=ax)
    for lab, color in LABEL_COLORS.items():
        edges = [(u, v) for u, v, d in g.edges(data=True) if d["label"] is lab]
        if edges:
            nx.draw_networkx_edges(g, pos, edgelist=edges, edge_color=color, width=2,
                                   arrowsize=16, node_size=900, connectionstyle="arc3,rad=0.08",
                                   ax=ax)
    nx.draw_networkx_edge_labels(g, pos, edge_labels={(u, v): d["label"].value
                                                      for u, v, d in g.edges(data=True)},
                                 font_size=7, ax=ax, rotate=False,
                                 bbox={"boxstyle": "round,pad=0.1", "fc": "white", "ec": "none",
                                       "alpha": 0.8})
    handles = [Line2D([], [], color=c, lw=2, label=lab.value) for lab, c in LABEL_COLORS.items()
               if any(d["label"] is lab for _, _, d in g.edges(data=True))]
    ax.legend(handles=handles, loc="lower right", fontsize=8, frameon=False)
    ax.set_title(f"{title or topology.name}: {topology.n_roads} roads, {topology.n_ramps} ramps, "
                 f"{topology.shape}", fontsize=10)
    ax.set_axis_off()
    ax.set_aspect("equal")
    fig.tight_layout()
    fig.savefig(path, metadata={"Software": None})
    plt.close(fig)
