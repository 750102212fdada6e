"""Coverage-guided sampling of geometric features (paper §III-C, Definition 4).

For each topology class, the feature sets to build are the rows of a small
t-way covering array over the features of its roads and ramps
(:mod:`flyover.sampling.covering`), under a regulation profile's value
domains and forbidden combinations (:mod:`flyover.sampling.model`).
"""

from flyover.sampling.constraints import Constraints, Forbidden, UnsatisfiableError
from flyover.sampling.covering import CoveringArray, SearchBudget, covering_array
from flyover.sampling.tuples import Coverage, TupleSpace, measure_coverage

__all__ = [
    "Forbidden", "Constraints", "UnsatisfiableError",
    "CoveringArray", "SearchBudget", "covering_array",
    "Coverage", "TupleSpace", "measure_coverage",
]
