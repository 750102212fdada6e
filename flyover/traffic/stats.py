"""Statistics of the throughput experiment (paper §IV-B, Fig. 6, Tables II–III), with scipy.

Per density:

``scope = "class"``
    Welch's t-test (unequal variances) between every pair of classes on
    their samples' stable throughputs (``a``, ``b``: class ids).
``scope = "sample"``
    Welch's t-test between every pair of samples of one class, on the
    per-interval throughputs of their stable windows (``a``, ``b``:
    ``{class_id}/{sample}``), as the paper compares samples of one class.
``scope = "inter_class_std"`` / ``"intra_class_std"``
    Table III: the standard deviation of the class means (``a = "*"``), and
    per class the standard deviation of its samples' throughputs (``a`` =
    class id; ``a = "*"`` their mean over the classes).

Runs that failed (``ok`` False) are left out; runs flagged for teleports or
collisions are kept and counted in ``n_flagged_a``/``n_flagged_b``, so no
statistic hides them. A test with fewer than two values on a side, or no
variance, has NaN statistics.
"""

from __future__ import annotations

import itertools
import logging
import math
from collections import defaultdict
from typing import Sequence

import numpy as np
import pyarrow as pa

__all__ = ["STATS_SCHEMA", "welch", "throughput_stats"]

log = logging.getLogger(__name__)

STATS_SCHEMA = pa.schema([
    ("density_veh_h", pa.float64()), ("scope", pa.string()), ("a", pa.string()),
    ("b", pa.string()), ("t_stat", pa.float64()), ("p_value", pa.float64()),
    ("n_a", pa.int64()), ("n_b", pa.int64()), ("mean_a_veh_h", pa.float64()),
    ("mean_b_veh_h", pa.float64()), ("std_veh_h", pa.float64()),
    ("n_flagged_a", pa.int64()), ("n_flagged_b", pa.int64()),
])

_NAN = float("nan")


def welch(a: Sequence[float], b: Sequence[float]) -> tuple[float, float]:
    """``(t, p)`` of Welch's two-sided t-test; NaN when either side has < 2 values or no spread.

    >>> t, p = welch([1.0, 2.0, 3.0], [4.0, 5.0, 6.5])
    >>> round(t, 3), p < 0.05
    (-3.413, True)
    """
    from scipy import stats  # noqa: PLC0415

    a, b = np.asarray(a, float), np.asarray(b, float)
    if len(a) < 2 or len(b) < 2 or (a.std() == 0 and b.std() == 0):
        return _NAN, _NAN
    res = stats.ttest_ind(a, b, equal_var=False)
    return float(res.statistic), float(res.pvalue)


def _std(x) -> float:
    return float(np.std(x, ddof=1)) if len(x) >= 2 else _NAN


def _row(d, scope, a, b="", t=_NAN, p=_NAN, na=0, nb=0, ma=_NAN, mb=_NAN, sd=_NAN, fa=0, fb=0):
    return {"density_veh_h": float(d), "scope": scope, "a": a, "b": b, "t_stat": t, "p_value": p,
            "n_a": int(na), "n_b": int(nb), "mean_a_veh_h": ma, "mean_b_veh_h": mb,
            "std_veh_h": sd, "n_flagged_a": int(fa), "n_flagged_b": int(fb)}


def throughput_stats(rows: Sequence[dict], series: Sequence[dict] = ()) -> list[dict]:
    """Rows of ``throughput_stats.parquet`` from throughput rows and their time series."""
    ok = [r for r in rows if r["ok"] and not math.isnan(r["throughput_veh_h"])]
    out: list[dict] = []
    window = {(r["class_id"], r["sample"], r["density_veh_h"]): r["stable_from_s"] for r in ok}
    per_interval: dict[tuple, list[float]] = defaultdict(list)
    for s in series:
        key = (s["class_id"], s["sample"], s["density_veh_h"])
        if key in window and s["t_s"] >= window[key] - 1e-9:
            per_interval[key].append(s["left"])
    interval = {}
    for s in series:  # interval length per run (t_s steps)
        interval.setdefault((s["class_id"], s["sample"], s["density_veh_h"]), []).append(s["t_s"])
    for d in sorted({r["density_veh_h"] for r in ok}):
        by_class: dict[str, list[dict]] = defaultdict(list)
        for r in ok:
            if r["density_veh_h"] == d:
                by_class[r["class_id"]].append(r)
        tp = {c: [r["throughput_veh_h"] for r in v] for c, v in by_class.items()}
        fl = {c: sum(r["flagged"] for r in v) for c, v in by_class.items()}
        for a, b in itertools.combinations(sorted(by_class), 2):
            t, p = welch(tp[a], tp[b])
            out.append(_row(d, "class", a, b, t, p, len(tp[a]), len(tp[b]), float(np.mean(tp[a])),
                            float(np.mean(tp[b])), fa=fl[a], fb=fl[b]))
        for c in sorted(by_class):
            runs = sorted(by_class[c], key=lambda r: r["sample"])
            for ra, rb in itertools.combinations(runs, 2):
                ka, kb = [(c, r["sample"], d) for r in (ra, rb)]
                xa, xb = [np.asarray(per_interval.get(k, []), float) * 3600.0 / _dt(interval, k)
                          for k in (ka, kb)]
                t, p = welch(xa, xb)
                out.append(_row(d, "sample", f"{c}/{ra['sample']}", f"{c}/{rb['sample']}", t, p,
                                len(xa), len(xb), float(xa.mean()) if len(xa) else _NAN,
                                float(xb.mean()) if len(xb) else _NAN,
                                fa=int(ra["flagged"]), fb=int(rb["flagged"])))
        means = [float(np.mean(tp[c])) for c in sorted(tp)]
        out.append(_row(d, "inter_class_std", "*", na=len(means), sd=_std(means),
                        fa=sum(fl.values())))
        intra = []
        for c in sorted(tp):
            sd = _std(tp[c])
            intra.append(sd)
            out.append(_row(d, "intra_class_std", c, na=len(tp[c]), ma=float(np.mean(tp[c])),
                            sd=sd, fa=fl[c]))
        finite = [x for x in intra if not math.isnan(x)]
        out.append(_row(d, "intra_class_std", "*", na=len(finite),
                        sd=float(np.mean(finite)) if finite else _NAN, fa=sum(fl.values())))
    return out


def _dt(interval: dict, key) -> float:
    ts = sorted(interval.get(key, [0.0, 1.0]))
    return float(ts[1] - ts[0]) if len(ts) > 1 else 1.0
