"""The paper's figures of the throughput experiment (matplotlib, png).

* :func:`plot_series` — Fig. 4: vehicles entering and leaving over time, one
  interchange, a panel per density, the detected start of the stable window;
* :func:`plot_class_throughput` — Fig. 5: class-average stable throughput per
  density (bars: mean, whiskers: standard deviation over the samples), classes
  sorted by their throughput at the highest density; classes with runs flagged
  for teleports or collisions are marked ``*``;
* :func:`plot_pvalues` — Fig. 6: Welch p-values between classes, a heatmap
  per density.
"""

from __future__ import annotations

import math
import os
from collections import defaultdict
from typing import Mapping, Sequence

import numpy as np

from flyover.topology.io import atomic_write

__all__ = ["plot_series", "plot_class_throughput", "plot_pvalues", "class_names", "throughput_figures"]


def _pyplot():
    import matplotlib  # noqa: PLC0415

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt  # noqa: PLC0415

    return plt


def _save(fig, path: str | os.PathLike) -> None:
    import io  # noqa: PLC0415

    buf = io.BytesIO()
    fig.savefig(buf, format="png", dpi=120, metadata={"Software": None})
    _pyplot().close(fig)
    atomic_write(path, buf.getvalue())


def _name(names: Mapping[str, str], c: str) -> str:
    return names.get(c, c)


def plot_series(series: Sequence[dict], rows: Sequence[dict], path: str | os.PathLike, *,
                title: str = "") -> None:
    """Fig. 4 for the interchange whose ``series`` rows are given (every density)."""
    plt = _pyplot()
    by_d: dict[float, list[dict]] = defaultdict(list)
    for s in series:
        by_d[s["density_veh_h"]].append(s)
    stable = {r["density_veh_h"]: r for r in rows}
    ds = sorted(by_d)
    fig, axes = plt.subplots(1, max(len(ds), 1), figsize=(4 * max(len(ds), 1), 3.4), sharey=True,
                             squeeze=False)
    for ax, d in zip(axes[0], ds):
        pts = sorted(by_d[d], key=lambda s: s["t_s"])
        t = np.array([s["t_s"] for s in pts])
        dt = t[1] - t[0] if len(t) > 1 else 1.0
        ax.step(t + dt, [s["entered"] * 3600 / dt for s in pts], where="pre", label="entering")
        ax.step(t + dt, [s["left"] * 3600 / dt for s in pts], where="pre", label="leaving")
        r = stable.get(d)
        if r is not None and not math.isnan(r["stable_from_s"]):
            ax.axvline(r["stable_from_s"], color="k", ls="--", lw=0.8)
            ax.axhline(r["throughput_veh_h"], color="C1", ls=":", lw=1.0)
        ax.set_title(f"{d:g} veh/h per movement", fontsize=9)
        ax.set_xlabel("time (s)")
    axes[0][0].set_ylabel("vehicles per hour")
    axes[0][0].legend(fontsize=8, loc="lower right")
    fig.suptitle(title or "vehicles entering and leaving (dashed: stable from)", fontsize=10)
    fig.tight_layout()
    _save(fig, path)


def _class_table(rows: Sequence[dict]):
    ok = [r for r in rows if r["ok"] and not math.isnan(r["throughput_veh_h"])]
    ds = sorted({r["density_veh_h"] for r in ok})
    vals: dict[tuple[str, float], list[float]] = defaultdict(list)
    flagged: set[str] = set()
    for r in ok:
        vals[(r["class_id"], r["density_veh_h"])].append(r["throughput_veh_h"])
        if r["flagged"]:
            flagged.add(r["class_id"])
    classes = sorted({r["class_id"] for r in ok})
    return ds, classes, vals, flagged


def plot_class_throughput(rows: Sequence[dict], names: Mapping[str, str],
                          path: str | os.PathLike) -> None:
    """Fig. 5: class-average stable throughput per density (``names``: class id → name)."""
    plt = _pyplot()
    ds, classes, vals, flagged = _class_table(rows)
    top = ds[-1] if ds else 0.0
    classes.sort(key=lambda c: (-np.mean(vals.get((c, top), [0.0])), _name(names, c)))
    fig, ax = plt.subplots(figsize=(max(6.0, 0.9 * len(classes) + 2), 4.2))
    width = 0.8 / max(len(ds), 1)
    x = np.arange(len(classes))
    for i, d in enumerate(ds):
        m = [np.mean(vals[(c, d)]) if vals.get((c, d)) else np.nan for c in classes]
        sd = [np.std(vals[(c, d)], ddof=1) if len(vals.get((c, d), [])) > 1 else 0.0
              for c in classes]
        ax.bar(x + (i - (len(ds) - 1) / 2) * width, m, width, yerr=sd, capsize=2,
               label=f"{d:g} veh/h per movement")
    ax.set_xticks(x, [_name(names, c) + ("*" if c in flagged else "") for c in classes],
                  rotation=35, ha="right", fontsize=8)
    ax.set_ylabel("stable throughput (veh/h)")
    ax.set_title("class-average stable throughput (whiskers: sd over samples)"
                 + (" (* runs with teleports/collisions)" if flagged else ""), fontsize=10)
    ax.legend(fontsize=8)
    fig.tight_layout()
    _save(fig, path)


def plot_pvalues(stats: Sequence[dict], names: Mapping[str, str], path: str | os.PathLike) -> None:
    """Fig. 6: p-values of Welch's t-test between classes, one heatmap per density."""
    plt = _pyplot()
    tests = [s for s in stats if s["scope"] == "class"]
    ds = sorted({s["density_veh_h"] for s in tests})
    classes = sorted({s["a"] for s in tests} | {s["b"] for s in tests},
                     key=lambda c: _name(names, c))
    idx = {c: i for i, c in enumerate(classes)}
    n = max(len(ds), 1)
    fig, axes = plt.subplots(1, n, figsize=(3.6 * n + 1.2, 4.4), squeeze=False,
                             layout="constrained")
    im = None
    for ax, d in zip(axes[0], ds):
        m = np.full((len(classes), len(classes)), np.nan)
        for s in tests:
            if s["density_veh_h"] == d:
                m[idx[s["a"]], idx[s["b"]]] = m[idx[s["b"]], idx[s["a"]]] = s["p_value"]
        im = ax.imshow(m, vmin=0.0, vmax=1.0, cmap="viridis")
        labels = [_name(names, c) for c in classes]
        ax.set_xticks(range(len(classes)), labels, rotation=90, fontsize=7)
        ax.set_yticks(range(len(classes)), labels if ax is axes[0][0] else [""] * len(classes),
                      fontsize=7)
        for i in range(len(classes)):
            for j in range(len(classes)):
                if not np.isnan(m[i, j]) and m[i, j] >= 0.05:
                    ax.text(j, i, f"{m[i, j]:.2f}", ha="center", va="center", fontsize=5,
                            color="w")
        ax.set_title(f"{d:g} veh/h", fontsize=9)
    if im is not None:
        fig.colorbar(im, ax=list(axes[0]), shrink=0.7, label="p-value (Welch)")
    fig.suptitle("p-values between classes (shown where >= 0.05)", fontsize=10)
    _save(fig, path)


def class_names(classes_table: str | os.PathLike) -> dict[str, str]:
    """class id → class name, from ``classes.parquet``."""
    import pyarrow.parquet as pq  # noqa: PLC0415

    t = pq.read_table(classes_table, columns=["class_id", "class_name"]).to_pylist()
    return {r["class_id"]: r["class_name"] for r in sorted(t, key=lambda r: r["class_id"])}


def throughput_figures(rows: Sequence[dict], stats: Sequence[dict], series: Sequence[dict],
                       names: Mapping[str, str], fig4: str | os.PathLike,
                       fig5: str | os.PathLike, fig6: str | os.PathLike) -> None:
    """Fig. 4 (the first interchange, by class name and sample, that ran), Fig. 5 and Fig. 6."""
    ran = sorted({(_name(names, r["class_id"]), r["class_id"], r["sample"]) for r in rows
                  if r["ok"]})
    if ran:
        _, c, s = ran[0]
        plot_series([x for x in series if x["class_id"] == c and x["sample"] == s],
                    [r for r in rows if r["class_id"] == c and r["sample"] == s and r["ok"]], fig4,
                    title=f"{_name(names, c)} sample {s}: vehicles entering and leaving "
                          "(dashed: stable from; dotted: stable throughput)")
    else:
        plot_series([], [], fig4, title="no run completed")
    plot_class_throughput(rows, names, fig5)
    plot_pvalues(stats, names, fig6)
