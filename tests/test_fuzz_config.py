"""Fuzzing the config loader (``flyover/config.py``, issue 19).

Seed: the repository's ``config/config.yaml``, mutated as data (values swapped for
hostile ones, keys dropped or added, city names that are paths) and as text
(lines dropped, duplicated, swapped; YAML tricks pasted in). Each either
validates or raises a ConfigError naming the file.
"""

from __future__ import annotations

import pytest
import yaml
from hypothesis import given
from hypothesis import strategies as st

from flyover.config import load_config
from flyover.errors import ConfigError
from tests.conftest import REPO
from tests.fuzz_support import (
    FUZZ,
    HOSTILE_WORDS,
    assert_names_file,
    loads_or_names_file,
    mutated_doc,
    mutated_yaml_text,
    sandbox,
    write_text,
)

CONFIG = REPO / "config" / "config.yaml"
TEXT = CONFIG.read_text(encoding="utf-8")
DOC = yaml.safe_load(TEXT)
WORDS = ["seed", "cities", "cities_dir", "topology", "sampling", "geometry", "osm", "export", "t", "profile",
         "china", "profiles", "lanes", "radius_m", "slope_pct", "elements", "kind", "ramp", "road", "where",
         "connected", "any", "de", "engine", "scipy", "catalog", "../../x", "a b"]


def _check(text: str) -> None:
    with sandbox() as root:
        loads_or_names_file(load_config, write_text(root / "config.yaml", text))


@FUZZ
@given(doc=mutated_doc([DOC], WORDS))
def test_fuzz_config_data_mutations_validate_or_name_the_file(doc):
    _check(yaml.safe_dump(doc, allow_unicode=True, sort_keys=False))


@FUZZ
@given(text=mutated_yaml_text([TEXT], WORDS))
def test_fuzz_config_text_mutations_validate_or_name_the_file(text):
    _check(text)


@FUZZ
@given(city=st.sampled_from(HOSTILE_WORDS) | st.text(max_size=20))
def test_fuzz_city_names_in_config_are_safe_names_or_refused(city):
    from flyover.topology.names import is_safe_name

    with sandbox() as root:
        path = write_text(root / "config.yaml", yaml.safe_dump({**DOC, "cities": [city]}))
        cfg = loads_or_names_file(load_config, path)
    assert (cfg is not None) == is_safe_name(city)


# -- what the fuzzers found, kept as plain regression tests ----------------------------------

@pytest.mark.parametrize("text, reason", [
    ("seed: 1\n1: x\n", "keys must be text"),
    ("seed: 2023-13-45\n", "malformed YAML"),
    ("- a\n- b\n", "must be a mapping"),
    ("cities: [..]\n", "cities.0"),
    ('cities: ["ok\\n"]\n', "cities.0"),
    (b"seed: 1 # caf\xe9\n", "not UTF-8"),
])
def test_config_tricks_are_one_line_errors(tmp_path, text, reason):
    path = tmp_path / "config.yaml"
    path.write_bytes(text if isinstance(text, bytes) else text.encode())
    with pytest.raises(ConfigError, match=reason) as info:
        load_config(path)
    assert_names_file(info.value, path)
