"""Names that become paths (issue 19): the safe set, the OSM mapping, cities, the import."""

from __future__ import annotations

import pytest
from hypothesis import given
from hypothesis import strategies as st

from flyover.errors import UnsafeNameError
from flyover.topology.catalog import catalog_dir
from flyover.topology.city import city_names, import_city
from flyover.topology.names import MAX_NAME_LENGTH, check_name, child_path, is_safe_name, safe_name
from tests.fuzz_support import FUZZ


@pytest.mark.parametrize("name", ["j1", "cloverleaf_cd", "A41_A43_1260536824", "v1.2", "x" * MAX_NAME_LENGTH])
def test_safe_names_pass(name):
    assert check_name(name) == name


@pytest.mark.parametrize("name", ["", ".", "..", "../x", "a/b", "a\\b", "/abs", ".hidden", "-opt", "_x",
                                  "a b", "café", "x" * (MAX_NAME_LENGTH + 1), "a\n", "a\x00", "C:x"])
def test_unsafe_names_are_refused_in_one_line_naming_file_and_name(name):
    with pytest.raises(UnsafeNameError) as info:
        check_name(name, source="city/spec.yaml")
    text = str(info.value)
    assert text.startswith("city/spec.yaml: ") and "unsafe interchange name" in text and "\n" not in text
    assert info.value.element == repr(name)[:2 * MAX_NAME_LENGTH] + ("..." if len(repr(name)) > 200 else "")


@FUZZ
@given(text=st.text(max_size=300))
def test_safe_name_maps_any_text_to_a_safe_stable_name(text):
    name = safe_name(text)
    assert is_safe_name(name) and name == safe_name(text)
    if is_safe_name(text) and not text.endswith((".", "-", "_")):
        assert name == text  # safe text is kept as it is


def test_safe_name_keeps_distinct_long_texts_apart():
    a, b = safe_name("A" * 200 + "1"), safe_name("A" * 200 + "2")
    assert a != b and len(a) == len(b) == MAX_NAME_LENGTH


def test_child_path_stays_in_its_folder(tmp_path):
    assert child_path(tmp_path, "j1", ".graphml") == tmp_path / "j1.graphml"
    with pytest.raises(UnsafeNameError):
        child_path(tmp_path, "../j1", ".graphml")


def test_unsafe_city_name_stops_the_import_before_writing(tmp_path):
    out = tmp_path / "results" / "topology" / "x"
    with pytest.raises(UnsafeNameError, match=r"'\.\./x': unsafe city name"):
        import_city("../x", [catalog_dir() / "j1.yaml"], out)
    assert not (tmp_path / "results").exists()


def test_names_differing_only_in_case_are_one_name_in_a_city(tmp_path):
    text = (catalog_dir() / "j1.yaml").read_text()
    (tmp_path / "a.yaml").write_text(text)
    (tmp_path / "b.yaml").write_text(text.replace("name: j1", "name: J1"))
    index = import_city("c", [tmp_path / "a.yaml", tmp_path / "b.yaml"], tmp_path / "out")
    assert [i["interchange"] for i in index["interchanges"]] == ["j1"]
    assert index["rejected"][0]["reason"] == "duplicate interchange name in this city (case ignored)"
    assert sorted(p.name for p in (tmp_path / "out").iterdir()) == ["index.json", "j1.graphml"]


def test_city_folders_must_have_safe_names(tmp_path):
    for name in ("berlin", "munich_2024", ".hidden"):
        (tmp_path / name).mkdir()
    assert city_names(tmp_path) == ["berlin", "munich_2024"]
    assert city_names(tmp_path, ["z", "a"]) == ["a", "z"]
    (tmp_path / "new york").mkdir()
    with pytest.raises(UnsafeNameError, match=r"new york: 'new york': unsafe city name"):
        city_names(tmp_path)
    with pytest.raises(UnsafeNameError, match="unsafe city name"):
        city_names(tmp_path, ["../etc"])
