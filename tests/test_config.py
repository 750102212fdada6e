"""The workflow configuration and its JSON schema."""

from __future__ import annotations

import pytest

from flyover.config import load_config, validate_config
from flyover.errors import ConfigError
from tests.conftest import REPO


def test_repository_config_validates_and_gets_defaults():
    cfg = load_config(REPO / "config" / "config.yaml")
    assert cfg["seed"] >= 0 and cfg["cities_dir"] == "config/cities"
    assert cfg["topology"]["catalog_names"] is True


@pytest.mark.parametrize("doc, element", [
    ({"seed": -1}, "seed"),
    ({"seed": 1, "cities": ["ok", "no/slash"]}, "cities.1"),
    ({"seed": 1, "colour": "blue"}, "(top level)"),
    ({"seed": 1, "topology": {"catalog_names": "yes"}}, "topology.catalog_names"),
])
def test_bad_config_names_the_key(doc, element):
    with pytest.raises(ConfigError) as info:
        validate_config(doc, "config.yaml")
    assert info.value.element == element
    assert str(info.value).startswith(f"config.yaml: {element}: ")
