"""flyover plugin ``truck_fuel``: fuel of a 40 t articulated truck on every ramp.

A lattice planner makes the trajectory, an LQR controller (python-control)
tracks it on a single-track truck model integrated by CasADi, and a
Willans-line engine model turns traction power into fuel (see README.md).
Registered under the entry-point group ``flyover.plugins``; rows go to the
table ``fuel``.
"""

__version__ = "0.1.0"
__all__ = ["__version__"]
