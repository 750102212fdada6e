"""Which side traffic drives on: a ``driving_side`` tag, else the country (coarse boxes).

>>> driving_side_at(-33.86, 151.21)  # Sydney
'left'
>>> driving_side_at(45.52, -122.68)  # Portland OR
'right'
"""

from __future__ import annotations

__all__ = ["driving_side_at"]

# (min_lon, min_lat, max_lon, max_lat, side), first match wins: right-hand exceptions
# inside a left-hand box come first. Coarse country outlines (where motorways are).
_BOXES = (
    (113.52, 22.10, 113.60, 22.22, "left"),    # Macau
    (113.80, 22.10, 114.45, 22.60, "left"),    # Hong Kong
    (116.90, 4.50, 127.00, 21.20, "right"),    # Philippines
    (100.00, 9.50, 108.00, 23.50, "right"),    # Laos, Cambodia, Vietnam
    (92.20, 9.50, 101.20, 28.60, "right"),     # Myanmar
    (78.00, 30.50, 135.00, 54.00, "right"),    # China, Korea (north of the boxes below)
    (124.00, 33.00, 129.45, 43.00, "right"),   # Korea
    (11.60, -18.10, 24.10, -4.30, "right"),    # Angola
    (28.80, -4.50, 30.90, -1.00, "right"),     # Rwanda, Burundi
    (-10.70, 49.80, 1.80, 60.90, "left"),      # Great Britain, Ireland
    (112.00, -44.00, 154.00, -10.00, "left"),  # Australia
    (166.00, -48.00, 179.00, -34.00, "left"),  # New Zealand
    (129.45, 30.00, 146.00, 45.60, "left"),    # Japan
    (60.50, 23.50, 77.90, 37.10, "left"),      # Pakistan
    (68.00, 5.90, 92.70, 30.50, "left"),       # India, Nepal, Bangladesh, Sri Lanka
    (97.30, 5.60, 105.70, 20.50, "left"),      # Thailand
    (95.00, -11.00, 141.00, 7.50, "left"),     # Malaysia, Singapore, Indonesia
    (11.70, -35.00, 41.00, -8.00, "left"),     # southern Africa
    (29.00, -12.00, 42.00, 5.00, "left"),      # Kenya, Tanzania, Uganda
    (32.20, 34.50, 34.70, 35.80, "left"),      # Cyprus
    (14.10, 35.70, 14.70, 36.10, "left"),      # Malta
    (-62.00, 10.00, -60.40, 11.50, "left"),    # Trinidad and Tobago
)


def driving_side_at(lat: float, lon: float) -> str:
    """``"left"`` or ``"right"``: the side traffic keeps to at ``(lat, lon)`` (right by default)."""
    for x0, y0, x1, y1, side in _BOXES:
        if x0 <= lon <= x1 and y0 <= lat <= y1:
            return side
    return "right"
