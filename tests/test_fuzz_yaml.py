"""Fuzzing the YAML spec reader and the city import of YAML specs (issue 19).

Inputs are the catalog's specs (``flyover/catalog/*.yaml``) mutated as data
(values swapped for hostile ones, keys dropped or added, names that are paths)
and as text (lines dropped, duplicated, swapped; YAML tricks pasted in). Each
either loads or raises a FlyoverError naming the file; the city import writes
nothing outside its output folder. Settings and the long run: ``tests/fuzz_support.py``.
"""

from __future__ import annotations

from pathlib import Path

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from flyover.errors import InputFormatError, TopologyError, UnsafeNameError
from flyover.topology.catalog import catalog_dir
from flyover.topology.io import read_topologies, read_yaml_spec
from tests.fuzz_support import (
    FUZZ,
    HOSTILE_WORDS,
    YAML_SNIPPETS,
    assert_names_file,
    import_stays_inside,
    json_values,
    mutated_doc,
    mutated_yaml_text,
    loads_or_names_file,
    sandbox,
    write_text,
)

CATALOG = sorted(catalog_dir().glob("*.yaml"))
TEXTS = [p.read_text(encoding="utf-8") for p in CATALOG]
DOCS = [yaml.safe_load(t) for t in TEXTS]
WORDS = ["name", "expressways", "lanes", "ramps", "from", "to", "design", "source", "right", "left",
         "straight", "A1", "A2", "B1", "r1", "A1 right", "r1 left @0.5", "B2 straight", "A1 up",
         "A1 right @2", "A1 right @nan", "A1 right @", "@", "A1  right  @ 0.3"]



@st.composite
def mutated_spec_doc(draw):
    """A catalog spec with 1-4 data mutations (sometimes a hostile name)."""
    doc = draw(mutated_doc(DOCS, WORDS))
    if isinstance(doc, dict) and draw(st.integers(0, 3)) == 0:
        doc["name"] = draw(st.sampled_from(HOSTILE_WORDS) | st.text(max_size=30) | json_values(WORDS))
    return doc


FILE_STEMS = st.sampled_from(["spec", "J1-copy", "a b", ".", "x" * 120, "café", "-dash", "ok.v2"])


def _check_one(text: str, stem: str) -> None:
    with sandbox() as root:
        folder = root / "in"
        folder.mkdir()
        path = write_text(folder / f"{stem}.yaml", text)
        t = loads_or_names_file(read_yaml_spec, path)
        index = import_stays_inside([path], root)
        assert len(index["interchanges"]) == (t is not None)


@FUZZ
@given(doc=mutated_spec_doc(), stem=FILE_STEMS)
def test_fuzz_yaml_spec_data_mutations_load_or_name_the_file(doc, stem):
    _check_one(yaml.safe_dump(doc, allow_unicode=True, sort_keys=False), stem)


@FUZZ
@given(text=mutated_yaml_text(TEXTS, WORDS), stem=FILE_STEMS)
def test_fuzz_yaml_spec_text_mutations_load_or_name_the_file(text, stem):
    _check_one(text, stem)


# -- what the fuzzers found, kept as plain regression tests ----------------------------------

@pytest.mark.parametrize("snippet, reason", [
    ("x: &x [*x]\n", "recursive alias"),
    (YAML_SNIPPETS[2], "expands to more than"),
    ("d: 2023-13-45\n", "malformed YAML"),
    ("[" * 3000 + "]" * 3000 + "\n", r"nested more than 100 deep"),  # took PyYAML 7 s
    ("a:\n" + "".join(" " * (2 * i + 2) + "- \n" for i in range(1200)), "nested too deeply"),
])
def test_yaml_tricks_are_one_line_errors(tmp_path, snippet, reason):
    path = tmp_path / "trick.yaml"
    path.write_text(snippet)
    with pytest.raises(InputFormatError, match=reason) as info:
        read_topologies(path)
    assert_names_file(info.value, path)


def test_yaml_bytes_that_are_not_utf8_are_named(tmp_path):
    path = tmp_path / "latin1.yaml"
    path.write_bytes("name: caf\xe9\n".encode("latin-1"))
    with pytest.raises(InputFormatError, match="not UTF-8") as info:
        read_yaml_spec(path)
    assert_names_file(info.value, path)


@pytest.mark.parametrize("ends", ["{from: 5, to: A1 right}", "{from: {A1: right}, to: A1 right}"])
def test_endpoint_that_is_not_text_or_a_list_is_named(tmp_path, ends):
    path = tmp_path / "e.yaml"
    path.write_text(f"expressways: {{A: [A1, A2]}}\nramps:\n  r1: {ends}\n")
    with pytest.raises(InputFormatError, match="one endpoint or a list") as info:
        read_yaml_spec(path)
    assert info.value.element == "ramps.r1.from"


def test_endpoint_parsing_is_linear_in_its_length(tmp_path):
    """The endpoint regex backtracked quadratically on long runs of blanks; now split."""
    path = tmp_path / "blanks.yaml"
    path.write_text("expressways: {A: [A1, A2]}\nramps:\n  r1: {from: 'A1 right" + " " * 200_000
                    + "x', to: A2 right}\n")
    with pytest.raises(InputFormatError, match="is not '<node>"):
        read_yaml_spec(path)


def test_a_name_that_is_a_path_is_refused_naming_file_and_name(tmp_path):
    path = tmp_path / "evil.yaml"
    path.write_text((catalog_dir() / "j1.yaml").read_text().replace("name: j1", "name: ../../../../x"))
    with pytest.raises(UnsafeNameError) as info:
        read_yaml_spec(path)
    assert str(info.value).startswith(f"{path}: '../../../../x': unsafe interchange name")
    assert "A-Z a-z 0-9 . _ -" in str(info.value)


def test_city_import_of_a_path_name_writes_nothing_outside(tmp_path):
    src = tmp_path / "in" / "evil.yaml"
    src.parent.mkdir()
    src.write_text((catalog_dir() / "j1.yaml").read_text().replace("name: j1", "name: ../../../../x"))
    good = src.with_name("good.yaml")
    good.write_text((catalog_dir() / "j1.yaml").read_text())
    with sandbox() as root:
        index = import_stays_inside([src, good], root)
    assert [i["interchange"] for i in index["interchanges"]] == ["j1"]
    assert index["rejected"][0]["element"] == "'../../../../x'"
    assert not list(tmp_path.rglob("x.graphml")) and not Path("/x.graphml").exists()


@pytest.mark.parametrize("where", ["expressway", "ramp"])
def test_control_characters_in_ids_are_refused_at_read_not_crash_the_import(tmp_path, where):
    """Found by the long fuzz run: YAML escapes put control characters into ids, which GraphML
    cannot hold; the import crashed writing them (ValueError from lxml)."""
    exp, ramp = ('"B\\x08"', "r1") if where == "expressway" else ("B", '"r\\x01"')
    path = tmp_path / "ctrl.yaml"
    path.write_text(f"expressways: {{A: [A1, A2], {exp}: [B1, B2]}}\n"
                    f"ramps:\n  {ramp}: {{from: A1 right, to: B1 right}}\n  r2: {{from: B2 right, to: A2 right}}\n")
    with pytest.raises(TopologyError, match="must be printable text") as info:
        read_yaml_spec(path)
    assert_names_file(info.value, path)
    with sandbox() as root:
        index = import_stays_inside([path], root)
    assert not index["interchanges"] and "printable" in index["rejected"][0]["reason"]


def test_rejection_reason_from_data_with_line_breaks_stays_one_line(tmp_path):
    """Found by the long fuzz run: a key "\\n" gave the rejected row a reason with a raw line
    break (index.json, rejected.parquet); reason and element are now kept printable."""
    path = tmp_path / "in" / "k.yaml"
    path.parent.mkdir()
    path.write_text('"\\n": 1\nexpressways: {A: [A1]}\n')
    with sandbox() as root:
        index = import_stays_inside([path], root)
    [row] = index["rejected"]
    assert row["reason"] == "unknown key(s): \\n" and row["element"] == "\\n"
