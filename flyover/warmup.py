"""Compile flyover's numba kernels once, at set-up, instead of in the first workflow jobs.

The kernels are compiled with ``cache=True``: numba keeps the machine code in
``__pycache__`` beside their source and reuses it in every later process until
the source changes. Compiling them takes tens of seconds of CPU, which every
first job of a run (two at once with ``-j2``) would otherwise pay. ``./dev
setup`` runs this after installing:

    python -m flyover.warmup

It builds one small interchange of the catalog's J1 (the geometry kernels) and
a covering array on a tiny budget (the sampling kernels).
"""

from __future__ import annotations

import sys
import time

__all__ = ["warm_up", "main"]


def warm_up() -> float:
    """Run every compiled kernel once on a small input; returns the seconds it took."""
    from flyover.geometry.layout import RampFeatures, build_interchange  # noqa: PLC0415
    from flyover.sampling.covering import covering_array  # noqa: PLC0415
    from flyover.sampling.covering import SearchBudget  # noqa: PLC0415
    from flyover.topology.catalog import catalog_topologies  # noqa: PLC0415

    t0 = time.perf_counter()
    covering_array([3, 3, 8, 5, 8, 5], 2, seed=0, budget=SearchBudget(work=1_000_000))
    j1 = catalog_topologies()["j1"]
    ramps = {r: RampFeatures(100.0, 3.0) for r in j1.ramps}
    build_interchange(j1, {}, ramps, class_id="warmup", seed=0)
    return time.perf_counter() - t0


def main(argv: list[str] | None = None) -> int:
    seconds = warm_up()
    sys.stderr.write(f"flyover: numba kernels ready ({seconds:.0f} s)\n")
    return 0


if __name__ == "__main__":
    sys.exit(main())
