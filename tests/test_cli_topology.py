"""``flyover topology check`` and ``flyover classify`` as a user runs them."""

from __future__ import annotations

import json

from flyover.cli import main
from flyover.topology.catalog import catalog_dir


def test_topology_check_prints_one_summary_line_per_interchange(capsys):
    assert main(["topology", "check", str(catalog_dir() / "j1.yaml"), str(catalog_dir() / "trumpet.yaml")]) == 0
    lines = capsys.readouterr().out.strip().splitlines()
    assert len(lines) == 2
    assert lines[0].endswith("j1: 4 roads, 4 ramps, shape cross, Out-R=3 Out-L=1 In-R=3 In-L=1")
    assert "shape T" in lines[1] and "Out-M=1" in lines[1]


def test_topology_check_reports_bad_file_and_still_checks_the_rest(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("expressways: {A: [A1, A2]}\nramps:\n  u: {from: A1 right, to: A1 right}\n"
                   "  v: {from: A2 right, to: Z9 right}\n")
    status = main(["topology", "check", str(bad), str(catalog_dir() / "j1.yaml")])
    out, err = capsys.readouterr()
    assert status == 1
    assert "j1: 4 roads" in out
    assert err.strip() == f"error: {bad}: v->Z9: edge refers to unknown node 'Z9'"


def test_classify_json_lists_class_of_each_interchange(capsys):
    assert main(["classify", str(catalog_dir()), "--json"]) == 0
    doc = json.loads(capsys.readouterr().out)
    rows = doc["interchanges"]
    assert len(rows) == len(list(catalog_dir().glob("*.yaml")))
    assert len({r["class_id"] for r in rows}) == len(rows)
    assert {r["class_name"] for r in rows} >= {"cloverleaf", "trumpet", "stack4", "j1"}
    assert doc["rejected"] == []


def test_classify_groups_copies_into_one_class(tmp_path, capsys):
    for i in range(3):
        (tmp_path / f"copy{i}.yaml").write_text((catalog_dir() / "turbine.yaml").read_text()
                                                .replace("name: turbine", f"name: t{i}"))
    assert main(["classify", str(tmp_path)]) == 0
    out = capsys.readouterr().out.strip().splitlines()
    assert len(out) == 3 and len({line.split(": ")[2].split()[0] for line in out}) == 1
    assert all(" turbine " in line for line in out)
