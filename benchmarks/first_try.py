"""Which ramps miss their targets at the first try, and why (the workflow's feature sets).

Builds each feature set of ``results/features/{class_id}.parquet`` of the given designs
exactly as ``benchmarks/geometry.py --from-results`` does (same seeds, same resampler),
and for every ramp that misses its targets at the first try prints the fit it had then
(just before it is resampled): its held radius (lane centre, over
:data:`flyover.geometry._kernels.HOLD_M`) against its target (and its pointwise radius), its slope, its conflicts and
what it met at its level, where along it the radius is tightest and whether it bends
there with or against its turn, its turn, its Bézier pieces and leads, and its ends
(parent and window length, m).

Run (from the repository root, with a ``results/features`` folder from a workflow run):
``PYTHONPATH=. .venv/bin/python benchmarks/first_try.py turbine directional_t --samples 0-20``;
``--drawn 8``: the feature sets ``benchmarks/geometry.py --samples 8`` draws instead.
The first try is captured by wrapping the build loop's ``_systematic`` test (called on
the first-try fit right before the first resample), so this follows
:mod:`flyover.geometry.build`; a ramp that was never resampled (systematically
infeasible) is printed with the reason it was recorded with.
"""

from __future__ import annotations

import argparse
import math
import os

os.environ.setdefault("OMP_NUM_THREADS", "1")

import numpy as np  # noqa: E402

from flyover.config import load_config  # noqa: E402
from flyover.geometry import build as build_mod  # noqa: E402
from flyover.geometry import state as state_mod  # noqa: E402
from flyover.geometry._kernels import HOLD_M  # noqa: E402
from flyover.geometry.bezier import lane_radius, sample_spline  # noqa: E402
from flyover.geometry.fit import conflicts_with  # noqa: E402
from flyover.geometry.layout import LayoutSettings  # noqa: E402
from flyover.geometry.tables import (  # noqa: E402
    build_sample, domain_resampler, read_feature_sets, sample_seed,
)
from flyover.topology.canonical import class_id as class_id_of  # noqa: E402
from flyover.topology.catalog import catalog_topologies  # noqa: E402


class _FirstTries:
    """Records each ramp's first-try fit (and what it met) when it is first resampled."""

    def __init__(self):
        self.fits: dict[str, tuple] = {}
        self._state = None
        self._last = None
        systematic, init = build_mod._systematic, state_mod.LayoutState.__init__

        def seen_systematic(fit):
            self._last = fit
            return systematic(fit)

        def seen_init(state, *args, **kw):
            init(state, *args, **kw)
            self._state = state

        build_mod._systematic = seen_systematic
        state_mod.LayoutState.__init__ = seen_init

    def resampler(self, inner):
        tries = self

        class Resampler:
            def __call__(self, ramp, attempt, radii):
                if attempt == 1 and ramp not in tries.fits and tries._last is not None:
                    fit, st = tries._last, tries._state
                    met = conflicts_with(fit, st.obstacles(), st.st.fit) if fit.conflicts else {}
                    tries.fits[ramp] = (fit, met)
                return inner(ramp, attempt, radii)

            def clearing(self, ramp, attempt, radii):
                return inner.clearing(ramp, attempt, radii)

        return Resampler()


def tightest(fit) -> tuple[float, float, bool]:
    """Where (m from the start) the held radius is tightest, the length, and whether the
    curve bends there against the ramp's turn."""
    smp = sample_spline(fit.ctrl, 400)
    s, tan = smp.s.ravel(), smp.tangent.reshape(-1, 2)
    head = np.unwrap(np.arctan2(tan[:, 1], tan[:, 0]))
    k = np.searchsorted(s, s + HOLD_M, side="left")
    ok = k < len(s)
    j = np.flatnonzero(ok)
    if not len(j):
        return 0.0, float(s[-1]), False
    kap = (head[k[ok]] - head[j]) / (s[k[ok]] - s[j])
    i = int(np.argmin(lane_radius(kap, fit.spec.width_m)))
    return float(s[j[i]]), float(s[-1]), bool(kap[i] * fit.spec.turn_rad < 0)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("designs", nargs="+")
    ap.add_argument("--samples", default="", help="a range a-b of sample numbers (default: all)")
    ap.add_argument("--drawn", type=int, default=0,
                    help="this many feature sets drawn from the domains as benchmarks/geometry.py "
                         "draws them, instead of results/features")
    args = ap.parse_args()
    cfg = load_config("config/config.yaml")
    settings = LayoutSettings.from_config(cfg["geometry"])
    seed = int(cfg["seed"])
    tries = _FirstTries()
    topologies = catalog_topologies()
    for design in args.designs:
        topo = topologies[design]
        cid = class_id_of(topo)
        if args.drawn:
            from benchmarks.geometry import drawn_feature_sets  # noqa: PLC0415
            profile = cfg["sampling"]["profiles"][cfg["sampling"]["profile"]]
            sets = drawn_feature_sets(topo, profile, args.drawn, seed)
        else:
            sets = read_feature_sets(f"results/features/{cid}.parquet")
        picked = sorted(sets)
        if args.samples:
            lo, hi = (int(v) for v in args.samples.split("-"))
            picked = [s for s in picked if lo <= s <= hi]
        total = missed = 0
        for sample in picked:
            tries.fits.clear()
            own = sample_seed(seed, cid, sample)
            ic = build_sample(topo, sets[sample], class_id=cid, sample=sample, seed=seed,
                              settings=settings,
                              resampler=tries.resampler(domain_resampler(sets, own, topo, settings,
                                                                               sample)))
            for o in ic.outcomes:
                total += 1
                if o.first_try_ok:
                    continue
                missed += 1
                if o.ramp not in tries.fits:  # never resampled (a level ramp asked to climb)
                    print(f"{design} {sample} {o.ramp}: not resampled: {o.infeasible}")
                    continue
                fit, met = tries.fits[o.ramp]
                sp = fit.spec
                at, length, against = tightest(fit)
                ends = ", ".join(f"{r.parent} ({r.hi - r.lo:.0f} m)" for r in (sp.start, sp.end)
                                 if r is not None)
                print(f"{design} {sample} {o.ramp}: radius {fit.min_radius_m:.1f} / "
                      f"{sp.target_radius_m:g} (pointwise "
                      f"{getattr(fit, 'point_radius_m', math.nan):.1f}), slope {fit.max_slope_pct:.2f} / "
                      f"{sp.target_slope_pct:g}, conflicts {fit.conflicts}"
                      f"{' with ' + str(met) if met else ''}; "
                      f"tightest at {at:.0f} of {length:.0f} m "
                      f"({'against' if against else 'with'} its turn); turn "
                      f"{math.degrees(sp.turn_rad):.0f} deg, {sp.pieces} pieces, leads up to "
                      f"{', '.join('-' if v is None else f'{v:.0f} m' for v in sp.lead_m)}; "
                      f"ends {ends}", flush=True)
        print(f"{design}: {missed} of {total} ramps miss their targets at the first try")


if __name__ == "__main__":
    main()
