"""geometry.json round trip and compatibility."""

import json
import math

import pytest

from flyover.errors import InputFormatError
from flyover.geometry.model import (
    FORMAT, Attachment, BezierPiece, ElevationPoly, InterchangeGeometry, RampGeometry,
    RoadGeometry, read_geometry, write_geometry,
)


def _sample() -> InterchangeGeometry:
    road = RoadGeometry("A1", "A", 4, 0, 0.0, (-300.0, -1.0), 0.0, 600.0)
    ramp = RampGeometry(
        id="r1", lanes=1,
        plan=(BezierPiece(((0.0, -16.0), (50.0, -16.0), (100.0, -40.0), (120.0, -80.0)), 140.2),),
        elevation=(ElevationPoly(0.0, 0.0, 0.0, 0.001, -1e-6),),
        start=Attachment("A1", "Out-R", 300.0, -15.0, 0.0, 0.0),
        end=Attachment("B1", "In-R", 200.0, -15.0, -math.pi / 2, 6.5),
        target_radius_m=math.inf, target_slope_pct=3.0, min_radius_m=151.2,
        max_slope_pct=2.98, length_m=140.2, resamples=1)
    return InterchangeGeometry("c123", 2, 7, levels_m=(0.0, 6.5), roads=(road,), ramps=(ramp,))


def test_json_round_trip_is_identity_and_bytes_stable(tmp_path):
    g = _sample()
    text = g.to_json()
    assert InterchangeGeometry.from_json(text) == g
    path = tmp_path / "geometry.json"
    write_geometry(g, path)
    assert path.read_text() == text
    assert read_geometry(path) == g


def test_json_follows_contract_keys_and_writes_inf_as_string():
    d = json.loads(_sample().to_json())
    assert d["format"] == FORMAT
    ramp = d["ramps"][0]
    assert ramp["target_radius_m"] == "inf"
    assert set(ramp["start"]) == {"parent", "label", "s_m", "offset_m", "heading_rad", "z_m"}
    assert len(ramp["plan"][0]["p"]) == 4
    assert set(d["roads"][0]) >= {"id", "expressway", "lanes", "level", "z_m", "start",
                                  "heading_rad", "length_m"}


def test_unknown_keys_are_ignored():
    d = json.loads(_sample().to_json())
    d["future_key"] = 1
    d["ramps"][0]["future"] = {"x": 1}
    assert InterchangeGeometry.from_dict(d) == _sample()


def test_bad_file_names_the_file(tmp_path):
    path = tmp_path / "geometry.json"
    path.write_text('{"format": "other/1"}')
    with pytest.raises(InputFormatError, match="geometry.json"):
        read_geometry(path)
