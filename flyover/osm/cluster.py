"""Which groups of links make one interchange.

A *link group* is a connected set of ramps (links joined to one another) with the
carriageways it touches, each carriageway on a *corridor* (a motorway by its refs).
A group touching two or more corridors is part of a motorway-to-motorway interchange;
groups are then clustered into interchanges by three rules:

1. **Same two motorways, close.** Groups sharing two corridors whose links come
   within ``cluster_distance_m`` of each other (twice that when they touch a same
   carriageway: a split or merge without links a little away from the flyovers).
2. **Three or more motorways (a system interchange).** Groups sharing one corridor whose
   links come within ``SYSTEM_FACTOR × cluster_distance_m`` of each other: the pairwise
   pieces of a system interchange of three motorways (A–B, B–C, A–C ramps that never
   meet one another) are one interchange, not three.
3. Otherwise separate: interchanges further apart along one motorway stay two.

>>> import numpy as np
>>> far = np.array([[5000.0, 0.0]])
>>> cluster_link_groups([{"A", "B"}, {"B", "C"}, {"A", "C"}, {"A", "D"}],
...                     [{1}, {2}, {3}, {4}],
...                     [np.zeros((1, 2)), np.array([[200.0, 0.0]]), np.array([[0.0, 250.0]]), far],
...                     cluster_distance_m=600.0)
[[0, 1, 2], [3]]
"""

from __future__ import annotations

from collections import defaultdict
from collections.abc import Sequence

import numpy as np

__all__ = ["cluster_link_groups", "SHARED_CARRIAGEWAY_FACTOR", "SYSTEM_FACTOR"]

#: link groups of the same two corridors joined to a same carriageway cluster up to this
#: times ``cluster_distance_m``
SHARED_CARRIAGEWAY_FACTOR = 2.0
#: link groups sharing one corridor (a third motorway) cluster up to this times
#: ``cluster_distance_m``
SYSTEM_FACTOR = 0.5


def _min_distance(a: np.ndarray, b: np.ndarray) -> float:
    return float(np.sqrt(((a[:, None, :] - b[None, :, :]) ** 2).sum(-1)).min())


def cluster_link_groups(corridors: Sequence[set], carriageways: Sequence[set], points: Sequence[np.ndarray],
                        cluster_distance_m: float) -> list[list[int]]:
    """Clusters (lists of indices, each sorted, in order of their first index) of link groups
    that form one interchange (rules in the module's docstring).

    Parameters
    ----------
    corridors
        Per link group, the corridors it touches (only groups touching two or more are given).
    carriageways
        Per link group, the carriageways (road ids) it touches.
    points
        Per link group, the ``(n, 2)`` points of its links and junctions, in metres.
    cluster_distance_m
        The distance of rule 1 (``OsmOptions.cluster_distance_m``).
    """
    n = len(corridors)
    parent = list(range(n))

    def find(k):
        while parent[k] != k:
            parent[k] = parent[parent[k]]
            k = parent[k]
        return k

    lo = np.array([p.min(axis=0) for p in points]).reshape(-1, 2)
    hi = np.array([p.max(axis=0) for p in points]).reshape(-1, 2)
    for i in range(n):
        # the gap between bounding boxes is at most the least distance: pairs further apart
        # than their limit are not measured
        gap = np.hypot(*np.maximum(0.0, np.maximum(lo[i] - hi, lo - hi[i])).T)
        for j in range(i + 1, n):
            shared = len(corridors[i] & corridors[j])
            if shared >= 2:
                limit = cluster_distance_m * (SHARED_CARRIAGEWAY_FACTOR if carriageways[i] & carriageways[j]
                                              else 1.0)
            elif shared == 1:
                limit = cluster_distance_m * SYSTEM_FACTOR
            else:
                continue
            if gap[j] <= limit and find(i) != find(j) and _min_distance(points[i], points[j]) <= limit:
                ri, rj = find(i), find(j)
                parent[max(ri, rj)] = min(ri, rj)
    out: dict[int, list[int]] = defaultdict(list)
    for k in range(n):
        out[find(k)].append(k)
    return [out[r] for r in sorted(out)]
