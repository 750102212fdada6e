"""Step 4: concrete 3D interchanges (road layout + ramps fitted by differential evolution).

See :mod:`flyover.geometry.model` for the ``geometry.json`` contract.
"""

from flyover.geometry.model import (
    FORMAT,
    Attachment,
    BezierPiece,
    ElevationPoly,
    InterchangeGeometry,
    RampGeometry,
    RoadGeometry,
    read_geometry,
    write_geometry,
)

__all__ = [
    "FORMAT",
    "Attachment",
    "BezierPiece",
    "ElevationPoly",
    "InterchangeGeometry",
    "RampGeometry",
    "RoadGeometry",
    "read_geometry",
    "write_geometry",
]
