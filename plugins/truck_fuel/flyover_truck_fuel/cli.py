"""``flyover-truck-fuel``: the paper's Table IV grid, the HBEFA cross-check, one interchange.

    flyover-truck-fuel grid [--out DIR] [--radii R ...] [--slopes S ...] [--config FILE]
    flyover-truck-fuel hbefa [--config FILE] [--geometry geometry.json ...]
    flyover-truck-fuel interchange geometry.json [--config FILE]
"""

from __future__ import annotations

import argparse
import csv
import logging
import sys
from dataclasses import asdict
from pathlib import Path

__all__ = ["main"]


def _settings(path: str | None):
    from flyover_truck_fuel.params import settings  # noqa: PLC0415

    if not path:
        return settings({})
    import yaml  # noqa: PLC0415

    doc = yaml.safe_load(Path(path).read_text(encoding="utf-8")) or {}
    return settings((doc.get("plugins") or {}).get("truck_fuel") or {})


def _print_table(rows: list[dict], cols: list[str]) -> None:
    text = [[(f"{r[c]:.4g}" if isinstance(r[c], float) else str(r[c])) for c in cols]
            for r in rows]
    widths = [max(len(c), *(len(t[i]) for t in text)) for i, c in enumerate(cols)]
    print("  ".join(c.rjust(w) for c, w in zip(cols, widths)))
    for t in text:
        print("  ".join(v.rjust(w) for v, w in zip(t, widths)))


def _grid(args) -> int:
    from flyover_truck_fuel.grid import PAPER_RADII_M, PAPER_SLOPES_PCT, fuel_grid, plot_grid  # noqa: PLC0415,E501

    st = _settings(args.config)
    cells = fuel_grid(st, args.radii or PAPER_RADII_M, args.slopes or PAPER_SLOPES_PCT)
    out = Path(args.out)
    out.mkdir(parents=True, exist_ok=True)
    rows = [asdict(c) for c in cells]
    with open(out / "fuel_grid.csv", "w", newline="") as fh:
        w = csv.DictWriter(fh, fieldnames=list(rows[0]))
        w.writeheader()
        w.writerows(rows)
    plot_grid(cells, out / "fuel_grid.png")
    _print_table(rows, ["direction", "radius_m", "slope_pct", "length_m", "fuel_ml",
                        "fuel_ml_per_km", "mean_speed_mps", "max_lateral_accel_mps2",
                        "completed"])
    print(f"wrote {out / 'fuel_grid.csv'} and {out / 'fuel_grid.png'}")
    return 0 if all(c.completed for c in cells) else 1


def _hbefa(args) -> int:
    from flyover.geometry.model import read_geometry  # noqa: PLC0415

    from flyover_truck_fuel.hbefa import HBEFA_CLASS, crosscheck  # noqa: PLC0415
    from flyover_truck_fuel.route import ramp_route  # noqa: PLC0415

    st = _settings(args.config)
    routes = []
    for path in args.geometry or ():
        g = read_geometry(path)
        routes += [(f"{g.class_id}/{g.sample} {r.id}", ramp_route(g, r, st.route))
                   for r in g.ramps]
    checks = crosscheck(st, routes=routes)
    rows = [{"case": c.case, "grade_pct": c.grade_pct, "length_m": c.length_m,
             "ours_ml_per_km": c.ours_ml_per_km, "hbefa4_ml_per_km": c.hbefa_ml_per_km,
             "ours/hbefa": c.ratio} for c in checks]
    print(f"ours ({st.truck.mass_kg / 1000:g} t, Willans line) beside SUMO {HBEFA_CLASS}, "
          "same speed and grade profile")
    _print_table(rows, list(rows[0]))
    return 0


def _interchange(args) -> int:
    from flyover.geometry.model import read_geometry  # noqa: PLC0415

    from flyover_truck_fuel.plugin import COLUMNS, TruckFuelPlugin  # noqa: PLC0415

    g = read_geometry(args.geometry)
    cfg = {}
    if args.config:
        import yaml  # noqa: PLC0415

        doc = yaml.safe_load(Path(args.config).read_text(encoding="utf-8")) or {}
        cfg = (doc.get("plugins") or {}).get("truck_fuel") or {}
    rows = TruckFuelPlugin().evaluate(g, cfg)
    _print_table(rows, [c for c in COLUMNS if c not in ("class_id", "sample", "target_speed_mps")])
    return 0 if all(r["completed"] for r in rows) else 1


def main(argv: list[str] | None = None) -> int:
    ap = argparse.ArgumentParser(prog="flyover-truck-fuel", description=__doc__.splitlines()[0])
    ap.add_argument("-v", "--verbose", action="store_true")
    sub = ap.add_subparsers(dest="command", required=True)
    g = sub.add_parser("grid", help="the paper's Table IV: radius x slope, up and down, 10 m/s")
    g.add_argument("--out", default=".", help="folder for fuel_grid.csv and fuel_grid.png")
    g.add_argument("--radii", type=float, nargs="+", help="lane-centre radii (m)")
    g.add_argument("--slopes", type=float, nargs="+", help="slopes (%%)")
    g.add_argument("--config", help="a workflow config (its plugins.truck_fuel section)")
    g.set_defaults(func=_grid)
    h = sub.add_parser("hbefa", help="ours beside SUMO's HBEFA4 heavy truck (flat, up, down)")
    h.add_argument("--config")
    h.add_argument("--geometry", nargs="*", help="also every ramp of these geometry.json")
    h.set_defaults(func=_hbefa)
    i = sub.add_parser("interchange", help="the rows of one geometry.json")
    i.add_argument("geometry")
    i.add_argument("--config")
    i.set_defaults(func=_interchange)
    args = ap.parse_args(argv)
    logging.basicConfig(level=logging.INFO if args.verbose else logging.WARNING,
                        format="%(levelname)s %(name)s: %(message)s")
    from flyover.errors import FlyoverError  # noqa: PLC0415

    try:
        return args.func(args)
    except FlyoverError as exc:
        print(f"error: {exc.one_line()}", file=sys.stderr)
        return 1


if __name__ == "__main__":
    sys.exit(main())
