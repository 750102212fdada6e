"""Fitting one ramp by differential evolution (paper Algorithm 1).

The plan view of a ramp is a G1 chain of ``n`` cubic Bézier pieces. Its ends
lie on *rails* (the reference line of the parent road or ramp, at a lateral
offset) and take the parent's heading there, so position and heading at both
ends hold **by construction**; the optimiser chooses where along each rail the
ramp attaches, the tangent lengths, and the position, heading and tangent
lengths of the interior joints. A ramp whose end is not attached to anything
(a stub that splits into other ramps, or one formed by merging ramps) has a
*free* end whose pose, relative to the other end, is part of the search.

The vertical profile (:mod:`flyover.geometry.profile`) follows from the plan
length, so the maximum slope equals its target exactly whenever the ramp is
long enough; the search makes it long enough.

Objective (whole population at once, compiled: :mod:`flyover.geometry._kernels`): curvature variance + radius
error² + slope-length shortfall² (the paper's penalty), plus hard-constraint
penalties: wrong total turn (loops, cusps), same-level conflicts with roads
and already fitted ramps (the samples in conflict, plus how deep they are in,
so that the search feels its way out of one), curvature jumps at joints
(G2 preferred), and length over the ramp's bound (:meth:`RampSpec.max_length_m`: a
multiple of the least it needs; a candidate over it is never acceptable, and a fit over
it is not :attr:`RampFit.ok`: a ramp is never stretched to meet its targets).
The search (:func:`evolve`) is adaptive differential evolution (JADE:
current-to-pbest/1/bin with an archive, ``F`` and ``CR`` adapted from the
successful trials), one objective call per generation for the whole
population. It stops as soon as the best candidate meets the targets on fine
samples (after ``min_generations``), or after ``patience`` generations
without a 1 % improvement (it will not meet them). ``engine: scipy`` runs
scipy's ``differential_evolution`` on the same objective instead (the
benchmark's reference).

Radius targets apply to the ramp's **lane centre line** (``width_m / 2`` right
of the reference line), to the tightest radius it *holds* over
:data:`flyover.geometry._kernels.HOLD_M` (10 m) of arc: a curve tight only for a
few metres does not count as turning at that radius. It must not be tighter than that
either: the lane centre is nowhere (pointwise) tighter than 95 % of the target (the
search: 95.5 %, :data:`flyover.geometry._kernels.POINT_MARGIN`), since a vehicle follows the
curvature at every point (a short end leg of a cubic can turn at a tenth of the target
for a metre or two, and the exported road shows it as a heading step at a link).
A target of ``inf`` on a ramp that has to turn means
*no radius to match*: the ramp is fitted as the gentlest curve its ends allow
(curvature² is minimised instead of matching a radius), and its radius counts
as within tolerance when it is nowhere tighter than :attr:`RampSpec.inf_floor_m`
(``inf_reference_m``, 250 m, the radius it is built with; 5 % tolerance like a finite
target: :func:`flyover.geometry.straight.inf_met`, the benchmark's reading of the
exported ``.xodr`` too) — a gentlest curve with a kink in it is no straight ramp.
"""

from __future__ import annotations

import logging
import math
from dataclasses import dataclass, field, replace

import numpy as np
from scipy.optimize import differential_evolution

from flyover.geometry import _kernels
from flyover.geometry.bezier import (heading_vec, held_radius, lane_centre, lane_radius,
                                     sample_spline)
from flyover.geometry.profile import climb_distance, elevation_polys, max_grade
from flyover.geometry.model import BezierPiece, ElevationPoly
from flyover.geometry.straight import INF_REFERENCE_M, inf_met, radius_met

__all__ = ["Rail", "FreeEnd", "Obstacles", "RampSpec", "FitSettings", "RampFit", "fit_ramp",
           "ramp_objective", "ranked_starts", "conflicts_with", "recount"]

log = logging.getLogger(__name__)

#: shortest lead (m): a lead is always a real straight piece, never a degenerate one
LEAD_MIN_M = 1.0
#: narrowest cell (m) of the grid the conflict kernel buckets obstacle ramp points in
MIN_CELL_M = 6.0


@dataclass(frozen=True, eq=False)
class Rail:
    """Where one end of a ramp may attach: along a parent's reference line.

    ``s``, ``xy``, ``heading`` (unwrapped) and ``z`` are stations of the
    parent's reference line; the ramp's reference line sits ``offset_m`` to
    the left of it (negative = right) and may attach anywhere in ``lo..hi``.
    """

    parent: str
    label: str
    s: np.ndarray
    xy: np.ndarray
    heading: np.ndarray
    z: np.ndarray
    offset_m: float
    lo: float
    hi: float
    straight: bool = False

    @classmethod
    def line(cls, parent: str, label: str, origin, heading: float, z: float, offset_m: float,
             lo: float, hi: float) -> "Rail":
        """A rail along a straight line through ``origin`` (``s`` = signed distance)."""
        s = np.array([min(lo, -1e4), max(hi, 1e4)])
        xy = np.asarray(origin, float) + s[:, None] * heading_vec(heading)
        return cls(parent, label, s, xy, np.full(2, heading), np.full(2, z), offset_m, lo, hi,
                   straight=True)

    def at(self, s: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Points ``(P, 2)`` (offset applied), headings and heights at stations ``s``."""
        s = np.atleast_1d(np.asarray(s, float))
        x = np.interp(s, self.s, self.xy[:, 0])
        y = np.interp(s, self.s, self.xy[:, 1])
        h = np.interp(s, self.s, self.heading)
        z = np.interp(s, self.s, self.z)
        n = heading_vec(h + np.pi / 2)
        return np.stack([x, y], axis=-1) + self.offset_m * n, h, z

    def grade(self, s: float) -> float:
        """The parent's grade at station ``s`` (of the heights :meth:`at` interpolates)."""
        i = int(np.clip(np.searchsorted(self.s, s, side="right") - 1, 0, len(self.s) - 2))
        return float((self.z[i + 1] - self.z[i]) / max(self.s[i + 1] - self.s[i], 1e-9))


@dataclass(frozen=True)
class FreeEnd:
    """A free end, placed relative to the ramp's other (attached) end.

    ``forward``/``lateral`` (metres, lateral positive = left) and ``turn``
    (radians) are search ranges; ``z`` is the end's height.
    """

    forward: tuple[float, float]
    lateral: tuple[float, float]
    turn: tuple[float, float]
    z: float


@dataclass(eq=False)
class Obstacles:
    """Already placed elements a ramp must not meet at the same level.

    ``lines``: rows ``x0, y0, dx, dy, t_lo, t_hi, lat_lo, lat_hi, z`` (a road's
    driving band in its own frame). ``points``/``z``/``half_width``: lane-centre
    samples of fitted ramps. ``names`` label the lines and point groups.
    """

    lines: np.ndarray = field(default_factory=lambda: np.zeros((0, 9)))
    points: np.ndarray = field(default_factory=lambda: np.zeros((0, 2)))
    z: np.ndarray = field(default_factory=lambda: np.zeros(0))
    half_width: np.ndarray = field(default_factory=lambda: np.zeros(0))
    owner: tuple[str, ...] = ()
    line_names: tuple[str, ...] = ()

    def grid(self, cell: float, reach: float | None = None) -> tuple:
        """:attr:`points` bucketed in cells of side ``cell`` for the conflict kernel (cached
        per cell size). ``reach``: how far (m) from a stretch of lane centre a point can be
        met (default: half a cell); the kernel looks at the cells within it."""
        cache = self.__dict__.setdefault("_grids", {})
        if cell not in cache:
            order, starts, x0, y0, nx, ny = _kernels.grid(self.points, cell)
            pts = np.ascontiguousarray(self.points[order])
            z = np.ascontiguousarray(self.z[order], float)
            cache[cell] = (np.ascontiguousarray(pts[:, 0]), np.ascontiguousarray(pts[:, 1]), z,
                           np.ascontiguousarray(self.half_width[order], float),
                           starts, x0, y0, float(cell), nx, ny,
                           *_kernels.cell_heights(z, starts))
        g = cache[cell]
        return g[:8] + (float(0.5 * cell if reach is None else reach),) + g[8:]


@dataclass(frozen=True)
class RampSpec:
    """What one ramp has to be: its ends, turn, width and targets."""

    id: str
    start: Rail | None
    end: Rail | None
    free: FreeEnd | None
    turn_rad: float
    pieces: int
    width_m: float
    target_radius_m: float
    target_slope_pct: float
    z_crest: float | None = None
    #: longest straight lead (m) at the start / end, where the ramp runs along its
    #: parent's heading before it turns (e.g. climbing beside it); ``None``: no lead
    lead_m: tuple[float | None, float | None] = (None, None)
    #: an ``inf`` radius target: the lane-centre radius is never below 0.95 × this (m;
    #: :func:`flyover.geometry.straight.inf_met`): the radius an ``inf`` ramp is built with
    inf_floor_m: float = INF_REFERENCE_M
    #: the least (m) its plan needs: the shortest path between its windows at 0.95 × its
    #: radius, its turn at that radius (:meth:`flyover.geometry.specs.RampSpecs.least_m`)
    least_m: float = 0.0
    #: how many times the least it needs the ramp may be (``inf``: unbounded);
    #: see :meth:`max_length_m`
    length_ratio: float = math.inf
    #: what the ramp may use on top for its diverge / merge tapers (m)
    tapers_m: float = 0.0
    #: with no crest (``z_crest`` ``None``): reach the end's height as early as it can and
    #: run on at it, not the start's as long as it can (a ramp a child joins beside its
    #: road at that road's height: :func:`flyover.geometry.beside.merge_window`)
    end_z_first: bool = False

    @property
    def crest_at_end(self) -> bool:
        """Its crest is its end's height (:attr:`end_z_first` with no ``z_crest``)."""
        return self.z_crest is None and self.end_z_first

    def max_length_m(self, za: float, zc: float, zb: float, transition_m: float) -> float:
        """The longest this ramp may be with ends at heights ``za``, ``zb`` and crest ``zc``:
        ``length_ratio`` × the longer of :attr:`least_m` and its climb to its crest and down
        at its slope target (vertical curves of ``transition_m`` included), and its tapers
        (:func:`flyover.geometry._kernels.length_bound`, as the search bounds it)."""
        g = self.target_slope_pct / 100.0
        climb = 0.0 if g <= 0 else float(climb_distance(zc - za, g, transition_m)
                                          + climb_distance(zc - zb, g, transition_m))
        return float(_kernels.length_bound(float(self.least_m), climb,
                                           float(self.length_ratio), float(self.tapers_m)))

    def leads(self) -> tuple[bool, bool]:
        """Whether the start / end has a lead (only attached ends have one; both or neither)."""
        on = any(v is not None for v in self.lead_m)
        return (on and self.start is not None, on and self.end is not None)


@dataclass(frozen=True)
class FitSettings:
    """Settings of the search and the tolerances (from config ``geometry``)."""

    popsize: int = 4
    maxiter: int = 150
    min_generations: int = 10
    tol_radius: float = 0.05
    tol_slope_pp: float = 0.2
    accept_radius: float = 0.02
    clearance_m: float = 5.5
    transition_m: float = 40.0
    end_zone_m: float = 15.0
    margin_m: float = 0.5
    inf_reference_m: float = INF_REFERENCE_M
    compact_m: float = 500.0
    compact_weight: float = 0.02
    patience: int = 30
    conflict_weight: float = 2.0
    depth_weight: float = 0.25  # per metre a conflicting sample is in, relative to the count
    samples: int = 64
    vectorized: bool = True
    engine: str = "jade"


@dataclass(frozen=True)
class RampFit:
    """The fitted ramp, measured on the final curve (densely sampled)."""

    spec: RampSpec
    ctrl: np.ndarray
    start_s: float
    end_s: float
    start_pose: tuple[float, float, float, float]
    end_pose: tuple[float, float, float, float]
    elevation: tuple[ElevationPoly, ...]
    length_m: float
    min_radius_m: float
    max_slope_pct: float
    conflicts: int
    evaluations: int
    seconds: float
    z_crest: float
    #: the tightest lane-centre radius at any point (m), not held over any length
    point_radius_m: float = math.inf
    #: the longest it may be (:meth:`RampSpec.max_length_m` at its ends' heights and crest)
    max_length_m: float = math.inf

    @property
    def radius_ok(self) -> bool:
        """The held radius within 5 % of the target, and the lane centre nowhere
        (pointwise) tighter than 0.95 × the target; ``inf``: neither tighter than 0.95 ×
        :attr:`RampSpec.inf_floor_m` (:func:`flyover.geometry.straight.inf_met`, as the
        benchmark reads the exported ``.xodr``)."""
        t = self.spec.target_radius_m
        if math.isinf(t):
            return inf_met(min(self.min_radius_m, self.point_radius_m), self.spec.inf_floor_m)
        return radius_met(self.min_radius_m, t) and inf_met(self.point_radius_m, t)

    @property
    def slope_ok(self) -> bool:
        return abs(self.max_slope_pct - self.spec.target_slope_pct) <= 0.2

    @property
    def length_ok(self) -> bool:
        """No longer than its bound (:attr:`max_length_m`): a ramp is never stretched."""
        return self.length_m <= self.max_length_m

    @property
    def ok(self) -> bool:
        return self.radius_ok and self.slope_ok and self.length_ok and self.conflicts == 0

    def pieces(self) -> tuple[BezierPiece, ...]:
        smp = sample_spline(self.ctrl, 400)
        return tuple(BezierPiece(tuple(map(tuple, c.tolist())), float(l))
                     for c, l in zip(self.ctrl, smp.piece_length))


# -- decoding a population ----------------------------------------------------

def _n_vars(spec: RampSpec) -> int:
    n = (spec.start is not None) + (spec.end is not None) + (3 if spec.free else 0)
    return n + sum(spec.leads()) + 2 + 5 * (spec.pieces - 1)


def bounds(spec: RampSpec) -> list[tuple[float, float]]:
    """Search bounds of the decision vector of ``spec``."""
    b: list[tuple[float, float]] = []
    for rail in (spec.start, spec.end):
        if rail is not None:
            b.append((rail.lo, rail.hi))
    for on, longest in zip(spec.leads(), spec.lead_m):
        if on:
            b.append((LEAD_MIN_M, max(LEAD_MIN_M + 1.0, longest or 0.0)))
    if spec.free:
        b += [spec.free.forward, spec.free.lateral, spec.free.turn]
    b += [(0.05, 0.8), (0.05, 0.8)]
    for _ in range(spec.pieces - 1):
        b += [(-0.8, 0.8), (-2.0, 2.0), (-np.pi / 3, np.pi / 3), (0.05, 0.8), (0.05, 0.8)]
    return b


@dataclass(frozen=True)
class _Decoded:
    ctrl: np.ndarray  # (P, n, 4, 2)
    sa: np.ndarray
    sb: np.ndarray
    a: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]  # x, y, heading, z
    b: tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]
    turn: np.ndarray  # intended total heading change (P,)


def _rail_args(spec: RampSpec) -> tuple:
    """The decode kernel's description of ``spec``'s ends (rails as ``(5, K)`` arrays)."""
    def rail(r: Rail | None) -> tuple[np.ndarray, float]:
        if r is None:
            return np.zeros((5, 0)), 0.0
        return np.ascontiguousarray(np.vstack([r.s, r.xy[:, 0], r.xy[:, 1], r.heading, r.z]),
                                    float), float(r.offset_m)

    mode = 0 if spec.free is None else (1 if spec.start is not None else 2)
    return (int(spec.pieces), float(spec.turn_rad), *rail(spec.start), *rail(spec.end), mode,
            float(spec.free.z) if spec.free else 0.0, int(any(spec.leads())))


def _decode(spec: RampSpec, x: np.ndarray, rails: tuple | None = None) -> _Decoded:
    """Control points for decision vectors ``x`` of shape ``(D, P)``.

    Decision vector: the stations of the attached ends on their rails; the
    lengths of their straight leads (:attr:`RampSpec.lead_m`); for a
    free end its forward and lateral offset and extra turn; the tangent
    lengths at both ends (fractions of the piece chord); per interior joint
    its position (along / across the chord, fractions of it), its heading
    relative to an even share of the turn, and its two tangent lengths.
    """
    ctrl, st, poses, turn = _kernels.decode(np.ascontiguousarray(x, float), *(rails or _rail_args(spec)))
    return _Decoded(ctrl, st[0], st[1], tuple(poses[0]), tuple(poses[1]), turn)


def _crest(spec: RampSpec, za: np.ndarray, zb: np.ndarray) -> np.ndarray:
    if spec.crest_at_end:
        return np.asarray(zb, float).copy()
    top = np.maximum(za, zb)
    return top if spec.z_crest is None else np.maximum(top, spec.z_crest)


def _obstacle_args(spec: RampSpec, obstacles: Obstacles, settings: FitSettings) -> tuple:
    """The conflict kernel's arguments for one ramp: half width, clearance, roads, ramp grid."""
    hw = 0.5 * spec.width_m - settings.margin_m
    # how far from the lane centre an obstacle point can be met: the two half widths,
    # widened by half the points' spacing (the kernel's reach is sqrt((hw + phw)^2 +
    # (STEP_M / 2)^2), never more than this)
    reach = hw + (float(obstacles.half_width.max()) if len(obstacles.half_width) else 0.0) \
        + 0.5 * _kernels.STEP_M
    # cells about as wide as the reach: a stretch looks at ~3 x 3 of them (cells twice the
    # reach, 2 x 2 of them, hold about twice the points to test); no narrower than
    # MIN_CELL_M, so that a large interchange's grid stays small
    grid = obstacles.grid(float(max(MIN_CELL_M, np.ceil(reach))), reach)
    lines = np.ascontiguousarray(obstacles.lines, float).reshape(-1, 9)
    return (float(settings.end_zone_m), float(hw), float(settings.clearance_m), lines) + grid


def _self_gap(spec: RampSpec, search: bool = False) -> float:
    """How far apart along itself (m) a ramp's stretches must be to meet as a crossing
    (two widths, as :func:`flyover.geometry.check.same_level_conflicts`; the kernel
    tests only curves whose heading spans :data:`_kernels.SELF_TURN_RAD`). In the
    ``search``, only for a ramp meant to turn that far (loops: 0 for the others, whose
    searches stay as they were); a fitted ramp (:func:`recount`) is always tested, so one
    that loops over itself and turns back counts its conflicts and is fitted again."""
    if search and abs(spec.turn_rad) <= _kernels.SELF_TURN_RAD:
        return 0.0
    return 2.0 * float(spec.width_m)


def _conflicts(spec: RampSpec, xy, tangent, s, z, length, obstacles: Obstacles,
               settings: FitSettings, gap: float = 0.0) -> np.ndarray:
    """Number of lane-centre samples ``(P,)`` meeting an obstacle at the same level, and
    with ``gap`` > 0 the pairs of stretches where the ramp meets itself
    (:func:`_kernels.self_conflicts`)."""
    cx, cy = lane_centre(xy, tangent, spec.width_m)
    cx, cy = np.ascontiguousarray(cx), np.ascontiguousarray(cy)
    s = np.ascontiguousarray(s, float)
    z = np.ascontiguousarray(np.broadcast_to(z, s.shape), float)
    length = np.ascontiguousarray(length, float)
    args = _obstacle_args(spec, obstacles, settings)
    n = _kernels.conflicts(cx, cy, s, z, length, *args)[0]
    if gap:
        n = n + _kernels.self_conflicts(cx, cy, s, z, length, *args[:3], gap)[0]
    return n


def ramp_objective(spec: RampSpec, obstacles: Obstacles, settings: FitSettings):
    """The DE objective of ``spec``: ``f(x)`` with ``x`` of shape ``(D, P)`` → ``(P,)``.

    Also returns a function giving the per-candidate terms (name → ``(P,)``),
    for stopping and reports. ``f.table(x)`` gives the terms as rows
    (:data:`_kernels.TERMS`), ``f.energy(table)`` and ``f.acceptable(table)``
    the energies and which candidates meet the targets; all compiled.
    ``f.table(x, bound)`` skips the conflict search of candidates whose other
    terms already put their energy above ``bound`` (their energy is then ``inf``).
    """
    g = spec.target_slope_pct / 100.0
    stub = spec.free is not None
    args = (*_rail_args(spec), -np.inf if spec.z_crest is None else float(spec.z_crest),
            float(spec.crest_at_end), int(settings.samples),
            float(spec.width_m), float(g), float(settings.transition_m),
            float(spec.target_radius_m), float(settings.inf_reference_m),
            float(spec.inf_floor_m),
            float(settings.compact_m),
            # stubs (a free end: they split or merge later) are pulled gently toward the
            # centre, so that the ramps joining them stay compact
            float(stub and spec.start is not None and spec.start.straight),
            float(stub and spec.end is not None and spec.end.straight),
            *_obstacle_args(spec, obstacles, settings))
    weights = (float(settings.conflict_weight), float(settings.depth_weight),
               float(settings.compact_weight))
    w = np.array(weights)
    gap = _self_gap(spec, search=True)
    longest = (float(spec.least_m), float(spec.length_ratio), float(spec.tapers_m))

    def table(x: np.ndarray, bound: np.ndarray | None = None) -> np.ndarray:
        x = np.ascontiguousarray(x, float)
        b = np.full(x.shape[1], np.inf) if bound is None else np.ascontiguousarray(bound, float)
        return _kernels.objective_terms(x, *args, w, b, gap, *longest)

    def terms(x: np.ndarray) -> dict[str, np.ndarray]:
        return dict(zip(_kernels.TERMS, table(x)))

    def f(x: np.ndarray) -> np.ndarray:
        return _kernels.energy(table(x), *weights)

    f.table = table
    f.energy = lambda t: _kernels.energy(t, *weights)
    f.acceptable = lambda t: _kernels.acceptable(t, float(settings.accept_radius))
    return f, terms


# -- the search -----------------------------------------------------------------

@dataclass
class _Search:
    """Outcome of :func:`evolve`: best decision vector, its energy, effort."""

    x: np.ndarray
    fun: float
    evaluations: int
    generations: int


def evolve(f, bounds_: list[tuple[float, float]], popsize: int, maxiter: int, seed: int,
           stop=None, init: np.ndarray | None = None) -> _Search:
    """Adaptive differential evolution (JADE: current-to-pbest/1/bin with an archive).

    ``f`` maps a population ``(D, P)`` to energies ``(P,)`` in one call. ``F``
    and ``CR`` adapt per generation from the successful trials (Zhang &
    Sanderson, IEEE TEC 13(5), 2009; F is truncated to 0.05..1 instead of
    redrawn; a beaten parent enters the archive, replacing a random member once
    it holds ``NP``); a trial leaving the bounds is put halfway between its
    parent and the bound. The generation's arithmetic is compiled
    (:func:`_kernels.jade_trial`, :func:`_kernels.jade_select`). ``init`` rows (decision vectors) replace
    the first rows of the Latin-hypercube start. After each generation
    ``stop(population, energies, gen)`` may end the search: ``True`` returns
    the best candidate, an index returns that candidate, ``None`` goes on.
    If ``f.bounded``, trials are evaluated as ``f(trials, parent_energies)``: a trial
    that cannot beat its parent may be given any energy above its parent's (it is
    discarded all the same). Deterministic for a seed.
    """
    rng = np.random.default_rng(seed)
    bounded = getattr(f, "bounded", False)
    lo = np.array([b[0] for b in bounds_], float)
    hi = np.array([b[1] for b in bounds_], float)
    span = np.where(hi > lo, hi - lo, 1.0)
    d = len(lo)
    n = max(5, popsize * d)
    # Latin hypercube in the unit cube
    u = (rng.permuted(np.tile(np.arange(n), (d, 1)), axis=1).T + rng.random((n, d))) / n
    if init is not None and len(init):
        k = min(len(init), n // 2)
        u[:k] = np.clip((np.asarray(init, float)[:k] - lo) / span, 0.0, 1.0)
    pop = lo + u * span
    energy = np.asarray(f(pop.T), float)
    evals = n
    archive = np.empty((n, d))
    n_arch = 0
    mu_cr, mu_f, c = 0.5, 0.5, 0.1
    n_best = max(2, int(round(0.1 * n)))
    gen = 0
    ib = int(np.argmin(energy))
    while gen < maxiter:
        gen += 1
        # one block of uniforms per generation (see _kernels.jade_trial)
        u = rng.random((n, d + 9))
        trial, cr, fm = _kernels.jade_trial(pop, energy, archive, n_arch, u, mu_cr, mu_f,
                                            n_best, lo, hi)
        e_trial = np.asarray(f(trial.T, energy) if bounded else f(trial.T), float)
        evals += n
        n_arch, mu_cr, mu_f = _kernels.jade_select(pop, energy, trial, e_trial, cr, fm, archive,
                                                   n_arch, u[:, d + 8], mu_cr, mu_f, c)
        ib = int(np.argmin(energy))
        if stop is not None:
            verdict = stop(pop, energy, gen)
            if verdict is not None:
                ib = ib if verdict is True else int(verdict)
                break
    return _Search(pop[ib].copy(), float(energy[ib]), evals, gen)


def fit_ramp(spec: RampSpec, obstacles: Obstacles | None = None,
             settings: FitSettings | None = None, seed: int = 0,
             init: np.ndarray | None = None) -> RampFit:
    """Fit one ramp by differential evolution and measure the result.

    Parameters
    ----------
    spec
        Ends, turn, width and targets.
    obstacles
        Roads and ramps already placed (same-level conflicts are penalised).
    settings
        DE settings and tolerances.
    seed
        Seed of the search (same seed → same curve).
    init
        Decision vectors ``(k, D)`` the search starts from besides its random ones
        (e.g. :func:`flyover.geometry.guess.dubins_guess`; the ``jade`` engine only).
    """
    import time  # noqa: PLC0415

    obstacles = obstacles or Obstacles()
    settings = settings or FitSettings()
    f, _ = ramp_objective(spec, obstacles, settings)
    b = bounds(spec)
    gen = [0]
    count = [0]

    # candidates meeting the acceptance test on the coarse samples; only these are
    # checked again on fine samples (the lowest-energy few of the population, see stop)
    coarse_good: set[bytes] = set()

    def counted(x: np.ndarray, bound: np.ndarray | None = None) -> np.ndarray:
        count[0] += x.shape[1]
        t = f.table(x, bound)
        for j in np.flatnonzero(f.acceptable(t)):
            coarse_good.add(np.ascontiguousarray(x[:, j]).tobytes())
        return f.energy(t)

    counted.bounded = True  # see evolve: trials worse than their parents skip conflicts
    fine = None if settings.samples >= 64 else \
        ramp_objective(spec, obstacles, replace(settings, samples=64))[0]

    def good(xk: np.ndarray) -> bool:
        if np.ascontiguousarray(xk, float).tobytes() not in coarse_good:
            return False
        return fine is None or bool(fine.acceptable(fine.table(xk[:, None]))[0])

    best = [np.inf, 0]  # best energy so far, generation it last improved by 1 %

    # an ``inf`` radius asks for the gentlest curve the ends allow: smoothing goes on until
    # the search stagnates, then the best candidate meeting the targets is taken
    gentlest = math.isinf(spec.target_radius_m)

    def chosen(pop: np.ndarray, energy: np.ndarray) -> int | None:
        """The lowest-energy candidate that meets the targets on fine samples (of the
        best three that met them on coarse samples)."""
        tried = 0
        for j in np.argsort(energy, kind="stable"):
            if np.ascontiguousarray(pop[j]).tobytes() in coarse_good:
                if good(pop[j]):
                    return int(j)
                tried += 1
                if tried == 3:
                    break
        return None

    def stop(pop: np.ndarray, energy: np.ndarray, generation: int):
        gen[0] = generation
        fun = float(energy.min())
        if fun < best[0] - 0.01 * abs(best[0]) or not np.isfinite(best[0]):
            best[0], best[1] = fun, generation
        elif settings.patience and generation - best[1] >= settings.patience:
            # stagnated: more generations will not meet the targets (or smooth further)
            j = chosen(pop, energy) if gentlest and coarse_good else None
            return True if j is None else j
        if generation < settings.min_generations or not coarse_good or gentlest:
            return None
        return chosen(pop, energy)

    def scipy_stop(intermediate_result) -> bool:  # scipy passes the result by this name
        x = intermediate_result.x
        return stop(x[None], np.array([intermediate_result.fun]), gen[0] + 1) is not None

    t0 = time.perf_counter()
    if settings.engine == "jade":
        x_best = evolve(counted, b, settings.popsize, settings.maxiter, seed, stop,
                        init).x
    elif settings.vectorized:
        x_best = differential_evolution(
            counted, b, popsize=settings.popsize, maxiter=settings.maxiter, seed=seed, tol=1e-8,
            polish=False, vectorized=True, updating="deferred", init="sobol",
            callback=scipy_stop).x
    else:
        x_best = differential_evolution(
            lambda x: float(counted(x[:, None])[0]), b, popsize=settings.popsize,
            maxiter=settings.maxiter, seed=seed, tol=1e-8, polish=False, init="sobol",
            callback=scipy_stop).x
    seconds = time.perf_counter() - t0
    return measure(spec, x_best, obstacles, settings, count[0], seconds)


def measure(spec: RampSpec, x: np.ndarray, obstacles: Obstacles, settings: FitSettings,
            evaluations: int = 0, seconds: float = 0.0) -> RampFit:
    """Build the final ramp from decision vector ``x`` and measure it densely."""
    dec = _decode(spec, np.asarray(x, float)[:, None])
    pose = lambda e: tuple(float(v[0]) for v in e)  # noqa: E731
    return _measured(spec, dec.ctrl[0], float(dec.sa[0]), float(dec.sb[0]), pose(dec.a),
                     pose(dec.b), obstacles, settings, evaluations, seconds)


def measure_spline(spec: RampSpec, ctrl: np.ndarray, start_s: float, end_s: float,
                   obstacles: Obstacles, settings: FitSettings, seconds: float = 0.0) -> RampFit:
    """A ramp built without the search (plan ``ctrl`` ``(n, 4, 2)`` attached at stations
    ``start_s``/``end_s`` of its rails), measured as :func:`measure` measures a fit."""
    poses = []
    for rail, s_m in ((spec.start, start_s), (spec.end, end_s)):
        xy, h, z = rail.at(np.array([s_m]))
        poses.append((float(xy[0, 0]), float(xy[0, 1]), float(h[0]), float(z[0])))
    return _measured(spec, np.asarray(ctrl, float), float(start_s), float(end_s), poses[0],
                     poses[1], obstacles, settings, 0, seconds)


def _measured(spec: RampSpec, ctrl: np.ndarray, start_s: float, end_s: float, pose_a: tuple,
              pose_b: tuple, obstacles: Obstacles, settings: FitSettings, evaluations: int,
              seconds: float) -> RampFit:
    """The fit of plan ``ctrl`` between end poses ``(x, y, heading, z)``, measured densely:
    length, lane-centre minimum radius, grade line and its maximum slope, conflicts."""
    dense = sample_spline(ctrl, 400)
    length = float(dense.length)
    rmin = held_radius(dense, spec.width_m, _kernels.HOLD_M)
    rpt = float(lane_radius(dense.curvature, spec.width_m).min())
    za, zb = pose_a[3], pose_b[3]
    zc = float(_crest(spec, np.array([za]), np.array([zb]))[0])
    g = spec.target_slope_pct / 100.0
    # a ramp leaving (joining) a ramp on a grade starts (ends) at its grade: no kink
    ga = spec.start.grade(start_s) if spec.start is not None else 0.0
    gb = spec.end.grade(end_s) if spec.end is not None else 0.0
    polys = elevation_polys(length, za, zc, zb, g if g > 0 else 1.0, settings.transition_m,
                            ga, gb)
    slope = max_grade(polys, length) * 100.0
    fit = RampFit(spec, ctrl, start_s, end_s, pose_a, pose_b, polys, length, rmin, slope, 0,
                  evaluations, seconds, zc, rpt,
                  spec.max_length_m(za, zc, zb, settings.transition_m))
    return recount(fit, obstacles, settings)


def recount(fit: RampFit, obstacles: Obstacles, settings: FitSettings) -> RampFit:
    """``fit`` with its same-level conflicts counted again against ``obstacles`` and itself
    (as :func:`measure` counts them: 64 samples per piece)."""
    from flyover.geometry.profile import evaluate_polys  # noqa: PLC0415

    coarse = sample_spline(fit.ctrl, 64)
    z, _ = evaluate_polys(fit.elevation, coarse.s.ravel())
    conf = int(_conflicts(fit.spec, coarse.xy[None], coarse.tangent[None], coarse.s[None],
                          z[None], np.array([fit.length_m]), obstacles, settings,
                          _self_gap(fit.spec))[0])
    return replace(fit, conflicts=conf)


def conflicts_with(fit: RampFit, obstacles: Obstacles, settings: FitSettings) -> dict[str, int]:
    """What a fitted ramp meets at the same level: obstacle name → samples (as measured).

    The search's own test (:func:`_kernels.conflicts` on 64 lane-centre samples per
    piece, as :func:`recount`), run against one road or one ramp at a time.
    """
    from flyover.geometry.profile import evaluate_polys  # noqa: PLC0415

    coarse = sample_spline(fit.ctrl, 64)
    z, _ = evaluate_polys(fit.elevation, coarse.s.ravel())
    lines = np.asarray(obstacles.lines).reshape(-1, 9)
    line_names = obstacles.line_names or tuple(f"road {i}" for i in range(len(lines)))
    single = [(name, Obstacles(lines=row[None])) for row, name in zip(lines, line_names)]
    if len(obstacles.points):
        owner = np.asarray(obstacles.owner)
        for name in dict.fromkeys(obstacles.owner):
            k = owner == name
            single.append((name, Obstacles(points=obstacles.points[k], z=obstacles.z[k],
                                           half_width=obstacles.half_width[k],
                                           owner=(name,) * int(k.sum()))))
    out: dict[str, int] = {}
    for name, one in single:
        n = int(_conflicts(fit.spec, coarse.xy[None], coarse.tangent[None], coarse.s[None],
                           z[None], np.array([fit.length_m]), one, settings)[0])
        if n:
            out[name] = out.get(name, 0) + n
    return out


def ranked_starts(spec: RampSpec, obstacles: Obstacles | None, settings: FitSettings,
                  x: np.ndarray, k: int) -> np.ndarray:
    """The ``k`` rows of ``x`` (decision vectors ``(n, D)`` of ``spec``) to start a search
    from: those long enough to climb at the slope target first (no shortfall, within the
    length bound), then the fewest conflicting samples, then the lowest energy."""
    if len(x) == 0:
        return x
    f, _ = ramp_objective(spec, obstacles or Obstacles(), settings)
    t = f.table(np.ascontiguousarray(np.asarray(x, float).T))
    e = f.energy(t)
    long_enough = (t[2] == 0.0) & (t[10] == 0.0)
    order = np.lexsort((e, t[7], ~long_enough))
    return np.asarray(x)[order[:k]]
