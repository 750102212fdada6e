"""Plugin mechanism: entry-point discovery (installed, broken), config, the batch runner."""

from __future__ import annotations

import logging
import textwrap
from pathlib import Path

import duckdb
import pyarrow.parquet as pq
import pytest

from flyover.cli import main as flyover_main
from flyover.errors import ConfigError
from flyover.geometry.model import (
    Attachment, BezierPiece, ElevationPoly, InterchangeGeometry, RampGeometry, RoadGeometry,
    write_geometry,
)
from flyover.plugins import (
    PluginError, installed_plugins, load_plugin, plugin_config, plugin_entry_points,
    run_plugins_on_class,
)

DEMO = textwrap.dedent('''
    import pyarrow as pa

    class Demo:
        name = "demo"
        version = "1.2.3"
        table = "demo"

        def config_schema(self):
            return {"type": "object", "additionalProperties": False,
                    "properties": {"scale": {"type": "number", "default": 2.0}}}

        def schema(self):
            return pa.schema([("class_id", pa.string()), ("sample", pa.int64()),
                              ("ramp", pa.string()), ("value", pa.float64())])

        def evaluate(self, geometry, config):
            if geometry.sample == 1:
                raise RuntimeError("cannot evaluate sample 1")
            return [{"ramp": r.id, "value": config["scale"] * r.length_m}
                    for r in geometry.ramps]

    class NotAPlugin:
        name = "incomplete"
''')


@pytest.fixture
def fake_plugins(tmp_path, monkeypatch):
    """A distribution registering a working plugin, a broken one and two that break the contract."""
    site = tmp_path / "site"
    site.mkdir()
    (site / "demo_flyover_plugin.py").write_text(DEMO)
    info = site / "demo_flyover_plugins-1.0.dist-info"
    info.mkdir()
    (info / "METADATA").write_text("Metadata-Version: 2.1\nName: demo-flyover-plugins\n"
                                   "Version: 1.0\n")
    (info / "entry_points.txt").write_text(
        "[flyover.plugins]\n"
        "demo = demo_flyover_plugin:Demo\n"
        "broken = no_such_module_for_flyover_tests:Plugin\n"
        "wrongname = demo_flyover_plugin:Demo\n"
        "incomplete = demo_flyover_plugin:NotAPlugin\n")
    monkeypatch.syspath_prepend(str(site))
    return site


def _geometry(sample: int, class_id: str = "c0123456789") -> InterchangeGeometry:
    road = RoadGeometry("A1", "A", 2, 0, 0.0, (0.0, -200.0), 1.5707963, 400.0)
    piece = BezierPiece(((-7.5, -100.0), (-7.5, -60.0), (-30.0, -20.0), (-60.0, 0.0)), 120.0)
    ramp = RampGeometry("r1", 1, (piece,), (ElevationPoly(0.0, 0.0, 0.0, 0.0, 0.0),),
                        Attachment("A1", "Out-R", 100.0, -7.5, 1.5707963, 0.0),
                        Attachment("A1", "In-R", 300.0, -7.5, 1.5707963, 0.0),
                        60.0, 2.0, 60.0, 0.0, 120.0)
    return InterchangeGeometry(class_id, sample, 1, roads=(road,), ramps=(ramp,))


def _write(root: Path, *samples: int, class_id: str = "c0123456789") -> list[Path]:
    paths = []
    for s in samples:
        p = root / "interchanges" / class_id / str(s) / "geometry.json"
        p.parent.mkdir(parents=True, exist_ok=True)
        write_geometry(_geometry(s, class_id), p)
        paths.append(p)
    return paths


def test_installed_truck_fuel_plugin_is_discovered_with_its_table():
    names = {i.name: i for i in plugin_entry_points()}
    assert "truck_fuel" in names
    assert names["truck_fuel"].distribution == "flyover-truck-fuel"
    plugin = load_plugin("truck_fuel")
    assert (plugin.name, plugin.table) == ("truck_fuel", "fuel")
    assert "class_id" in plugin.schema().names and "sample" in plugin.schema().names


def test_broken_plugins_are_skipped_with_a_warning_naming_them(fake_plugins, caplog):
    with caplog.at_level(logging.WARNING, logger="flyover.plugins.registry"):
        loaded = installed_plugins()
    assert "demo" in loaded and loaded["demo"].version == "1.2.3"
    for bad in ("broken", "wrongname", "incomplete"):
        assert bad not in loaded
        assert any(f"broken plugin {bad}:" in r.getMessage() for r in caplog.records), bad
    with pytest.raises(PluginError, match="no_such_module_for_flyover_tests"):
        load_plugin("broken")
    with pytest.raises(PluginError, match="registered as 'wrongname'"):
        load_plugin("wrongname")
    with pytest.raises(PluginError, match="lacks"):
        load_plugin("incomplete")
    with pytest.raises(PluginError, match="no installed plugin"):
        load_plugin("nonexistent")


def test_plugins_command_lists_installed_and_broken(fake_plugins, capsys):
    status = flyover_main(["plugins"])
    out = capsys.readouterr().out
    assert status == 1  # a broken plugin is installed
    lines = {line.split()[0]: line for line in out.splitlines()[1:]}
    assert lines["demo"].split()[1:3] == ["1.2.3", "demo"]
    assert lines["truck_fuel"].split()[2] == "fuel"
    assert "BROKEN" in lines["broken"]


def test_plugin_config_fills_defaults_and_names_the_bad_key():
    schema = {"type": "object", "additionalProperties": False,
              "properties": {"a": {"type": "object", "default": {},
                                   "properties": {"x": {"type": "number", "default": 1.5}}}}}
    assert plugin_config(schema, None, plugin="p") == {"a": {"x": 1.5}}
    assert plugin_config(schema, {"a": {"x": 3}}, plugin="p") == {"a": {"x": 3}}
    with pytest.raises(ConfigError) as err:
        plugin_config(schema, {"a": {"x": "fast"}}, plugin="p", source="config.yaml")
    assert err.value.element == "plugins.p.a.x" and err.value.source == "config.yaml"


def test_batch_writes_hive_partitions_and_survives_a_failing_interchange(fake_plugins,
                                                                          tmp_path, caplog):
    res = tmp_path / "results"
    paths = _write(res, 0, 1, 2)
    paths.append(res / "interchanges" / "c0123456789" / "3" / "geometry.json")  # missing
    table = res / "plugins" / "demo" / "c0123456789.parquet"
    with caplog.at_level(logging.ERROR):
        run = run_plugins_on_class(paths, res, config={"demo": {"scale": 3.0}},
                                   plugins=["demo"], class_tables={"demo": table})
    (r,) = run.runs
    assert (r.plugin, r.version, r.table, r.interchanges, r.rows) == ("demo", "1.2.3", "demo", 4, 2)
    assert {Path(p).parent.name for p, _ in r.failures} == {"1", "3"}
    assert any("cannot evaluate sample 1" in why for _, why in r.failures)
    parts = sorted(res.glob("demo/class_id=*/sample=*/part-0.parquet"))
    assert [p.parent.name for p in parts] == ["sample=0", "sample=1", "sample=2", "sample=3"]
    assert not list(res.rglob("*.tmp"))
    # partition files hold the other columns; the path holds class_id and sample
    assert pq.read_schema(parts[0]).names == ["ramp", "value"]
    got = duckdb.sql(f"SELECT class_id, sample, ramp, value FROM read_parquet("
                     f"'{res}/demo/*/*/*.parquet', hive_partitioning = true) ORDER BY sample"
                     ).fetchall()
    assert got == [("c0123456789", 0, "r1", 360.0), ("c0123456789", 2, "r1", 360.0)]
    whole = pq.read_table(table)
    assert whole.column_names == ["class_id", "sample", "ramp", "value"]
    assert whole.column("sample").to_pylist() == [0, 2]


def test_batch_prunes_partitions_of_samples_no_longer_in_the_class(fake_plugins, tmp_path):
    res = tmp_path / "results"
    run_plugins_on_class(_write(res, 0, 2, 5), res, plugins=["demo"])
    assert (res / "demo" / "class_id=c0123456789" / "sample=5").exists()
    run_plugins_on_class(_write(res, 0, 2), res, plugins=["demo"])
    assert sorted(p.name for p in (res / "demo" / "class_id=c0123456789").iterdir()) == \
        ["sample=0", "sample=2"]


def test_batch_rejects_a_bad_config_section_before_any_work(fake_plugins, tmp_path):
    res = tmp_path / "results"
    with pytest.raises(ConfigError, match="plugins.demo"):
        run_plugins_on_class(_write(res, 0), res, plugins=["demo"], config={"demo": {"speed": 1}})
    assert not (res / "demo").exists()
