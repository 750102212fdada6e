"""Coverage-guided sampling of geometric features (paper §III-C, Definition 4).

For each topology class, the feature sets to build are the rows of a small
t-way covering array over the features of its roads and ramps
(:mod:`flyover.sampling.covering`), under a regulation profile's value
domains and forbidden combinations (:mod:`flyover.sampling.model`).

The names below are imported on first use, so that importing the package
(e.g. for the command line) does not load the compiled kernels.
"""

from __future__ import annotations

import importlib

_EXPORTS = {
    "Forbidden": "constraints", "Constraints": "constraints", "UnsatisfiableError": "constraints",
    "CoveringArray": "covering", "SearchBudget": "covering", "covering_array": "covering",
    "Coverage": "tuples", "TupleSpace": "tuples", "measure_coverage": "tuples",
    "Profile": "model", "feature_model": "model", "default_profile": "model",
    "Sampling": "sample", "sample_topology": "sample",
}

__all__ = list(_EXPORTS)


def __getattr__(name: str):
    if name in _EXPORTS:
        return getattr(importlib.import_module(f"{__name__}.{_EXPORTS[name]}"), name)
    raise AttributeError(f"module {__name__!r} has no attribute {name!r}")
