"""Pointwise radius of the ramps' lane centre lines against their radius targets.

The fit holds a ramp's radius over 10 m (:data:`flyover.geometry._kernels.HOLD_M`); a
vehicle follows the curvature at every point. This script measures, independently of the
fit, the **pointwise** radius of each ramp's lane centre: the curvature of each cubic
Bézier piece of ``geometry.json``'s plan, evaluated analytically at ``--per-piece``
parameter values per piece (default 2,000), offset to the lane centre (half the ramp's
lane width right of its reference line: ``|1/κ + w/2|``), its least value over the whole
ramp (nothing excluded: the straight leads have none). Target: its radius target, or
for an ``inf`` target the floor the fit holds it to (``inf_reference_m``,
:func:`flyover.geometry.straight.inf_met`).

Per design it prints the share of ramps whose pointwise minimum is below 0.5 × and below
0.95 × the target, where the minimum lies (``start``: the ramp's first curved point, at
its start or at the end of its straight lead; ``end`` likewise; ``join``: a joint between
two Bézier pieces; ``body``: inside a piece, more than ``--near`` metres from those), and
the share *within 5 % pointwise*: held radius within 5 % of the target (the fit's
measure, re-measured here) and nowhere tighter than 0.95 × the target.

With ``--xodr N`` it cross-checks the first N ramps of each design (and the ramps
``--show`` lists; ``--xodr-all``: every ramp, counted) on the exported
OpenDRIVE (written and read back, :mod:`flyover.opendrive`): the centre of the ramp's own
lanes (followed through the lane links, :func:`benchmarks.geometry.lane_centre_runs`),
sampled every 0.1 m; radius as heading change over arc length held over 2 m.

``--continuity``: every interchange is exported and its lane links checked
(:func:`flyover.opendrive.continuity.check_continuity`: 1 cm, 0.5°).

Input: directories of ``{class_id}/{sample}/geometry.json`` (``benchmarks/geometry.py
--keep DIR`` writes them; ``results/interchanges`` is the workflow's).

Run: ``PYTHONPATH=. .venv/bin/python benchmarks/pointwise_radius.py /tmp/pr18/before``
"""

from __future__ import annotations

import argparse
import io
import math
from pathlib import Path

import numpy as np

from flyover.config import load_config
from flyover.geometry.bezier import lane_radius
from flyover.geometry.layout import LayoutSettings
from flyover.geometry.model import InterchangeGeometry
from flyover.topology.canonical import class_id as class_id_of
from flyover.topology.catalog import catalog_topologies

WHERE = ("start", "end", "join", "body")


def piece_curvature(p: np.ndarray, m: int) -> tuple[np.ndarray, np.ndarray]:
    """Signed curvature and arc length (from the piece's start) at ``m`` parameter values of
    the cubic with control points ``p`` ``(4, 2)``."""
    t = np.linspace(0.0, 1.0, m)[:, None]
    u = 1.0 - t
    d1 = 3 * (u * u * (p[1] - p[0]) + 2 * u * t * (p[2] - p[1]) + t * t * (p[3] - p[2]))
    d2 = 6 * (u * (p[2] - 2 * p[1] + p[0]) + t * (p[3] - 2 * p[2] + p[1]))
    speed = np.hypot(d1[:, 0], d1[:, 1])
    kap = (d1[:, 0] * d2[:, 1] - d1[:, 1] * d2[:, 0]) / np.maximum(speed, 1e-12) ** 3
    s = np.concatenate([[0.0], np.cumsum(0.5 * (speed[1:] + speed[:-1]) / (m - 1))])
    return kap, s


def pointwise(ramp, width_m: float, m: int, near_m: float, hold_m: float = 10.0) -> dict:
    """A ramp's pointwise minimum lane-centre radius, where it lies, and its held radius."""
    kaps, ss, joints, straight = [], [], [0.0], []
    off = 0.0
    for piece in ramp.plan:
        p = np.asarray(piece.p, float)
        kap, s = piece_curvature(p, m)
        kaps.append(kap)
        ss.append(s + off)
        off += s[-1]
        joints.append(off)
        straight.append(bool(np.all(np.abs(kap) < 1e-12)))
    kap, s = np.concatenate(kaps), np.concatenate(ss)
    r = lane_radius(kap, width_m)
    i = int(np.argmin(r))
    curved = [k for k, st in enumerate(straight) if not st] or [0]
    first, last = joints[curved[0]], joints[curved[-1] + 1]
    at = float(s[i])
    if abs(at - first) <= near_m:
        where = "start"
    elif abs(at - last) <= near_m:
        where = "end"
    elif min(abs(at - j) for j in joints) <= near_m:
        where = "join"
    else:
        where = "body"
    # held radius (mean curvature over hold_m, as flyover.geometry.bezier.held_radius)
    turn = np.concatenate([[0.0], np.cumsum(0.5 * (kap[1:] + kap[:-1]) * np.diff(s))])
    hold = min(hold_m, 0.999 * float(s[-1]))
    k = np.searchsorted(s, s + hold, side="left")
    ok = k < len(s)
    j = np.flatnonzero(ok)
    with np.errstate(divide="ignore", invalid="ignore"):
        kh = (turn[k[ok]] - turn[j]) / np.maximum(s[k[ok]] - s[j], 1e-9)
    rh = lane_radius(kh, width_m)
    return {"r_point": float(r[i]), "where": where, "s": at, "length": float(s[-1]),
            "r_held": float(rh.min()) if len(rh) else math.inf}


def _held_min(xy: np.ndarray, hold_m: float, step_m: float) -> tuple[float, float, float]:
    """The least radius a polyline holds over ``hold_m`` (heading change over arc length,
    as :func:`benchmarks.geometry.held_radius_xy`), where (m from its start), its length."""
    cum = np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])
    if cum[-1] < hold_m + 2 * step_m:
        return math.inf, 0.0, float(cum[-1])
    s = np.arange(0.0, cum[-1] + 1e-9, step_m)
    p = np.column_stack([np.interp(s, cum, xy[:, 0]), np.interp(s, cum, xy[:, 1])])
    d = np.diff(p, axis=0)
    head = np.unwrap(np.arctan2(d[:, 1], d[:, 0]))
    mid = 0.5 * (s[1:] + s[:-1])
    k = np.searchsorted(mid, mid + hold_m, side="left")
    ok = k < len(mid)
    j = np.flatnonzero(ok)
    with np.errstate(divide="ignore"):
        r = (mid[k[ok]] - mid[j]) / np.abs(head[k[ok]] - head[j])
    i = int(np.argmin(r))
    return float(r[i]), float(mid[j[i]]), float(cum[-1])


def xodr_min_radius(geometry, step_m: float = 0.1, hold_m: float = 2.0,
                    taper_m: float = 20.0) -> dict[str, tuple[float, float]]:
    """Ramp id → the least radius of the centre of its own lanes in the exported .xodr,
    held over ``hold_m`` (heading change over arc length), sampled every ``step_m`` along
    all its roads (its junction connecting roads included); and the least more than
    ``taper_m`` from either end of the ramp (where it leaves or joins its parent, on a
    15 m connecting road whose lanes taper)."""
    from benchmarks.geometry import lane_centre_runs  # noqa: PLC0415
    from flyover.opendrive.reader import read_xodr  # noqa: PLC0415
    from flyover.opendrive.writer import xodr_bytes  # noqa: PLC0415

    net = read_xodr(io.BytesIO(xodr_bytes(geometry)))
    out = {}
    for name, (runs, _) in lane_centre_runs(geometry, net, step_m=step_m).items():
        every = inner = math.inf
        for xy in runs[0]:
            r, at, length = _held_min(xy, hold_m, step_m)
            every = min(every, r)
            if taper_m < at < length - taper_m - hold_m:
                inner = min(inner, r)
            elif length > 2 * taper_m + hold_m + 2 * step_m:
                r2, _, _ = _held_min(xy[int(taper_m / step_m):-int(taper_m / step_m)], hold_m,
                                     step_m)
                inner = min(inner, r2)
        out[name] = (every, inner)
    return out


def continuity(geometry) -> tuple[bool, str]:
    """The lane-link continuity check of the exported .xodr of ``geometry``."""
    from flyover.opendrive.continuity import check_continuity  # noqa: PLC0415
    from flyover.opendrive.reader import read_xodr  # noqa: PLC0415
    from flyover.opendrive.writer import xodr_bytes  # noqa: PLC0415

    return check_continuity(read_xodr(io.BytesIO(xodr_bytes(geometry))))


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("dirs", nargs="+", type=Path)
    ap.add_argument("--per-piece", type=int, default=2000)
    ap.add_argument("--near", type=float, default=3.0,
                    help="metres from a joint within which a minimum counts as at it")
    ap.add_argument("--xodr", type=int, default=0,
                    help="cross-check this many ramps per design on the exported .xodr")
    ap.add_argument("--show", type=int, default=0, help="list this many ramps below 0.95")
    ap.add_argument("--xodr-all", action="store_true",
                    help="cross-check every ramp on the exported .xodr (counts only)")
    ap.add_argument("--continuity", action="store_true",
                    help="also export every interchange and count those failing the lane-link "
                         "continuity check (flyover.opendrive.continuity, 1 cm / 0.5 deg)")
    args = ap.parse_args()
    cfg = load_config("config/config.yaml")
    floor = LayoutSettings.from_config(cfg["geometry"]).fit.inf_reference_m
    names = {class_id_of(t): n for n, t in catalog_topologies().items()}
    rows = []
    broken: list[str] = []
    n_ic = 0
    for d in args.dirs:
        for path in sorted(d.glob("*/*/geometry.json")):
            g = InterchangeGeometry.from_json(path.read_text())
            n_ic += 1
            if args.continuity:
                ok, detail = continuity(g)
                if not ok:
                    broken.append(f"{names.get(g.class_id, g.class_id)} {g.sample}: {detail}")
            for ramp in g.ramps:
                w = ramp.lanes * g.ramp_lane_width_m
                t = ramp.target_radius_m
                target = floor if math.isinf(t) else t
                row = pointwise(ramp, w, args.per_piece, args.near)
                row.update(design=names.get(g.class_id, g.class_id), sample=g.sample,
                           ramp=ramp.id, target=target, inf=math.isinf(t), ok=ramp.ok,
                           path=path)
                rows.append(row)
    by: dict[str, list[dict]] = {}
    for r in rows:
        by.setdefault(r["design"], []).append(r)
    print(f"pointwise lane-centre radius (analytic, {args.per_piece} points per Bezier piece) "
          "against the target (inf: the floor)")
    print(f"{'design':<18}{'ramps':>6}{'<0.5':>7}{'<0.95':>7}   <0.95 at start/end/join/body"
          f"{'held 5%':>10}{'held 5% & pw':>14}")

    def line(name, rs):
        n = len(rs)
        half = sum(r["r_point"] < 0.5 * r["target"] for r in rs)
        low = [r for r in rs if r["r_point"] < 0.95 * r["target"]]
        wh = "/".join(str(sum(r["where"] == w for r in low)) for w in WHERE)
        held = [r for r in rs if (r["r_held"] >= 0.95 * r["target"] if r["inf"]
                                  else abs(r["r_held"] - r["target"]) <= 0.05 * r["target"])]
        both = [r for r in held if r["r_point"] >= 0.95 * r["target"]]
        print(f"{name:<18}{n:6d}{100 * half / n:6.1f}%{100 * len(low) / n:6.1f}%   "
              f"{wh:<26}{100 * len(held) / n:9.1f}%{100 * len(both) / n:13.1f}%")

    for name, rs in sorted(by.items()):
        line(name, rs)
    line("total", rows)
    half_where = [r["where"] for r in rows if r["r_point"] < 0.5 * r["target"]]
    print("below 0.5 x target, at start/end/join/body: "
          + "/".join(str(half_where.count(w)) for w in WHERE))
    low = sorted((r for r in rows if r["r_point"] < 0.95 * r["target"]),
                 key=lambda r: r["r_point"] / r["target"])
    for r in low[: args.show]:
        print(f"  {r['design']} {r['sample']} {r['ramp']}: pointwise {r['r_point']:.1f} m at "
              f"{r['s']:.1f} of {r['length']:.0f} m ({r['where']}), held {r['r_held']:.1f}, "
              f"target {r['target']:g}{' (inf)' if r['inf'] else ''}, ok {r['ok']}")
    if args.continuity:
        print(f"interchanges failing the continuity check of their .xodr: {len(broken)} of {n_ic}")
        for b in broken:
            print(f"  {b}")
    # cross-check: the first --xodr ramps of each design's first sample, and the ramps listed
    xs, seen = [], {}
    for r in rows:
        if seen.get(r["design"], 0) < args.xodr and r["sample"] == min(
                q["sample"] for q in rows if q["design"] == r["design"]):
            seen[r["design"]] = seen.get(r["design"], 0) + 1
            xs.append(r)
    xs += [r for r in low[: args.show] if r not in xs] if args.xodr else []
    listed = len(xs)
    if args.xodr_all:
        xs += [r for r in rows if r not in xs]
    cache: dict[Path, dict] = {}
    for r in xs:
        if r["path"] not in cache:
            cache[r["path"]] = xodr_min_radius(
                InterchangeGeometry.from_json(r["path"].read_text()))
        r["xodr"], r["xodr_road"] = cache[r["path"]].get(r["ramp"], (math.nan, math.nan))
    if xs:
        print("cross-check on the exported .xodr (own lanes' centre, every 0.1 m, radius held "
              "over 2 m) against the analytic pointwise minimum:")
        n = len(xs)
        print(f"  {n} ramps: xodr below 0.5 x target {sum(r['xodr'] < 0.5 * r['target'] for r in xs)}"
              f", below 0.95 x {sum(r['xodr'] < 0.95 * r['target'] for r in xs)}; analytic "
              f"below 0.5 x {sum(r['r_point'] < 0.5 * r['target'] for r in xs)}, below 0.95 x "
              f"{sum(r['r_point'] < 0.95 * r['target'] for r in xs)}; xodr more than 20 m from "
              f"the ramp's ends (its tapers): below 0.5 x "
              f"{sum(r['xodr_road'] < 0.5 * r['target'] for r in xs)}, below 0.95 x "
              f"{sum(r['xodr_road'] < 0.95 * r['target'] for r in xs)}")
        bad = [r for r in xs if r["xodr"] < 0.95 * r["target"] and r["r_point"] >= 0.95 * r["target"]]
        for r in bad[: args.show]:
            print(f"  xodr only: {r['design']} {r['sample']} {r['ramp']}: xodr {r['xodr']:.1f}, "
                  f"beyond 20 m from its ends {r['xodr_road']:.1f}, pointwise {r['r_point']:.1f}"
                  f", target {r['target']:g}")
        for r in xs[:listed]:
            print(f"  {r['design']:<17} {r['sample']:3d} {r['ramp']:<6} target {r['target']:6g}"
                  f"  pointwise {r['r_point']:8.1f}  xodr {r['xodr']:8.1f}  (beyond 20 m from its "
                  f"ends {r['xodr_road']:8.1f})")


if __name__ == "__main__":
    main()
