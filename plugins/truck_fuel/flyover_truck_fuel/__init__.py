"""flyover plugin ``truck_fuel``: fuel of a 40 t articulated truck on every ramp.

A lattice planner makes the trajectory, an LQR controller (python-control)
tracks it on a single-track truck model integrated by CasADi, and a
Willans-line engine model turns traction power into fuel (see README.md).
Registered under the entry-point group ``flyover.plugins``; rows go to the
table ``fuel``. The plugin's version is its distribution's (one source:
``pyproject.toml``), so the workflow reruns when it changes.
"""

from importlib import metadata as _metadata

try:
    __version__ = _metadata.version("flyover-truck-fuel")
except _metadata.PackageNotFoundError:  # running from a source tree, not installed
    __version__ = "0.0.0+unknown"

__all__ = ["__version__"]
