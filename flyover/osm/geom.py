"""Plane geometry helpers for OSM polylines (local metres, numpy-vectorised)."""

from __future__ import annotations

import numpy as np

__all__ = ["LocalProjection", "arclength", "point_at", "min_radius", "segment_distances", "bearing_letter",
           "turn_deg", "signed_turn_deg", "run_beside"]

_EARTH_RADIUS_M = 6_371_008.8


class LocalProjection:
    """Equirectangular projection around ``origin`` (lat, lon): metres east, north.

    Accurate to well under a metre over the few kilometres of an interchange.
    """

    def __init__(self, lat0: float, lon0: float):
        self.lat0, self.lon0 = float(lat0), float(lon0)
        self._kx = np.radians(1.0) * _EARTH_RADIUS_M * np.cos(np.radians(self.lat0))
        self._ky = np.radians(1.0) * _EARTH_RADIUS_M

    def xy(self, lat: np.ndarray, lon: np.ndarray) -> np.ndarray:
        lat, lon = np.asarray(lat, float), np.asarray(lon, float)
        return np.column_stack([(lon - self.lon0) * self._kx, (lat - self.lat0) * self._ky])

    def latlon(self, xy: np.ndarray) -> np.ndarray:
        xy = np.atleast_2d(np.asarray(xy, float))
        return np.column_stack([xy[:, 1] / self._ky + self.lat0, xy[:, 0] / self._kx + self.lon0])


def arclength(xy: np.ndarray) -> np.ndarray:
    """Cumulative length along a polyline, starting at 0."""
    xy = np.asarray(xy, float)
    if len(xy) < 2:
        return np.zeros(len(xy))
    return np.concatenate([[0.0], np.cumsum(np.hypot(*np.diff(xy, axis=0).T))])


def point_at(xy: np.ndarray, s: float, cum: np.ndarray | None = None) -> np.ndarray:
    """The point at arclength ``s`` (clipped to the polyline); ``cum``: its
    :func:`arclength`, if already known."""
    xy = np.asarray(xy, float)
    cum = arclength(xy) if cum is None else cum
    s = float(np.clip(s, 0.0, cum[-1]))
    return np.array([np.interp(s, cum, xy[:, 0]), np.interp(s, cum, xy[:, 1])])


#: most resampled points :func:`min_radius` takes (a 1000 km polyline at 10 m)
MAX_SAMPLES = 100_000


def min_radius(xy: np.ndarray, step_m: float = 10.0, chord_steps: int = 3) -> float:
    """Smallest radius of curvature of a polyline, in metres (``inf`` if straight).

    The polyline is resampled every ``step_m`` (coarser for polylines longer than
    :data:`MAX_SAMPLES` steps, so the work stays bounded whatever the coordinates)
    and the circumradius of point triples ``chord_steps`` samples apart is taken,
    which smooths the noise of closely spaced OSM nodes.
    """
    xy = np.asarray(xy, float)
    cum = arclength(xy)
    if len(xy) < 3 or not np.isfinite(cum[-1]) or cum[-1] < 2 * chord_steps * step_m:
        return float("inf")
    step_m = max(step_m, float(cum[-1]) / MAX_SAMPLES)
    s = np.arange(0.0, cum[-1] + 1e-9, step_m)
    p = np.column_stack([np.interp(s, cum, xy[:, 0]), np.interp(s, cum, xy[:, 1])])
    k = chord_steps
    a, b, c = p[:-2 * k], p[k:-k], p[2 * k:]
    ab, bc, ca = (np.hypot(*(b - a).T), np.hypot(*(c - b).T), np.hypot(*(a - c).T))
    cross = np.abs((b - a)[:, 0] * (c - a)[:, 1] - (b - a)[:, 1] * (c - a)[:, 0])
    with np.errstate(divide="ignore", invalid="ignore"):
        r = ab * bc * ca / (2.0 * cross)
    r = r[np.isfinite(r)]
    return float(r.min()) if len(r) else float("inf")


def segment_distances(p: np.ndarray, a: np.ndarray, b: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Distance from point ``p`` to each segment ``a[i]-b[i]`` and the projection parameter t."""
    d = b - a
    len2 = np.einsum("ij,ij->i", d, d)
    with np.errstate(divide="ignore", invalid="ignore"):
        t = np.where(len2 > 0, np.einsum("ij,ij->i", p - a, d) / len2, 0.0)
    t = np.clip(t, 0.0, 1.0)
    proj = a + t[:, None] * d
    return np.hypot(*(p - proj).T), t


def bearing_letter(v: np.ndarray) -> str:
    """Compass letter (N, E, S, W) of a direction vector (x east, y north)."""
    ang = np.degrees(np.arctan2(v[0], v[1])) % 360.0
    return "NESW"[int(((ang + 45.0) % 360.0) // 90.0)]


def turn_deg(xy) -> float:
    """Total signed heading change along a polyline ``(n, 2)``, in degrees (absolute value);
    steps shorter than 0.5 m are skipped."""
    return abs(signed_turn_deg(xy))


def signed_turn_deg(xy) -> float:
    """Total heading change along a polyline ``(n, 2)``, in degrees, left (anticlockwise)
    positive and not wrapped (a cloverleaf loop about -270); steps shorter than 0.5 m are
    skipped.

    >>> round(signed_turn_deg([(0, 0), (10, 0), (10, 10), (0, 10)]))
    180
    """
    xy = np.asarray(xy, float).reshape(-1, 2)
    d = np.diff(xy, axis=0)
    d = d[np.hypot(*d.T) > 0.5]
    if len(d) < 2:
        return 0.0
    da = np.diff(np.arctan2(d[:, 1], d[:, 0]))
    return float(np.degrees(((da + np.pi) % (2 * np.pi) - np.pi).sum()))


def run_beside(line, other, separation_m: float, max_length_m: float) -> np.ndarray:
    """The beginning of polyline ``line`` while it stays within ``separation_m`` of polyline
    ``other`` (cut where it leaves, interpolated between vertices), at most ``max_length_m``
    long: where a carriageway that splits from another without a link runs beside it.

    Parameters
    ----------
    line, other
        Polylines ``(n, 2)`` in metres; ``line`` begins where it leaves ``other``.
    separation_m
        Distance from ``other`` at which the run ends.
    max_length_m
        Longest run, along ``line``.

    Returns
    -------
    numpy.ndarray
        The run ``(k, 2)``, from ``line[0]`` (a single point if ``other`` has no segment).

    >>> run_beside([[0, 0], [0, 100], [50, 200]], [[0, 0], [0, 300]], 10.0, 500.0).round(1).tolist()
    [[0.0, 0.0], [0.0, 100.0], [10.0, 120.0]]
    """
    line = np.asarray(line, float).reshape(-1, 2)
    other = np.asarray(other, float).reshape(-1, 2)
    if len(line) < 2 or len(other) < 2:
        return line[:1]
    cum = arclength(line)
    a, b = other[:-1], other[1:]
    # only the segments of ``other`` that the points measured (up to the first past
    # max_length_m along the line) can come within separation_m of
    last = min(int(np.searchsorted(cum, max_length_m, side="right")), len(line) - 1)
    near = segment_distances(line[0], a, b)[0] <= cum[last] + separation_m
    a, b = a[near], b[near]
    if not len(a):
        return line[:1]
    out, d_prev = [line[0]], float(segment_distances(line[0], a, b)[0].min())
    for k in range(1, len(line)):  # (distances measured only as far as the run goes)
        d = float(segment_distances(line[k], a, b)[0].min())
        if d > separation_m:
            t = (separation_m - d_prev) / (d - d_prev) if d > d_prev else 0.0
            out.append(line[k - 1] + float(np.clip(t, 0.0, 1.0)) * (line[k] - line[k - 1]))
            break
        if cum[k] > max_length_m:
            out.append(point_at(line, max_length_m))
            break
        out.append(line[k])
        d_prev = d
    return np.array(out)
