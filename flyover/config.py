"""Workflow configuration: loading and validation against the JSON schema."""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path
from typing import Any

import jsonschema
import yaml

from flyover.errors import ConfigError
from flyover.safe_yaml import load_yaml

__all__ = ["schema", "validate_config", "load_config", "DEFAULT_CONFIG"]

#: the repository's config file, used by the CLI when run from a checkout
DEFAULT_CONFIG = Path("config/config.yaml")


@lru_cache(maxsize=1)
def schema() -> dict[str, Any]:
    """The configuration's JSON schema (``flyover/schemas/config.schema.yaml``)."""
    text = (Path(__file__).parent / "schemas" / "config.schema.yaml").read_text(encoding="utf-8")
    return yaml.safe_load(text)


def _with_defaults(validator_class):
    validate_properties = validator_class.VALIDATORS["properties"]

    def set_defaults(validator, properties, instance, sch):
        if isinstance(instance, dict):
            for prop, sub in properties.items():
                if "default" in sub:
                    instance.setdefault(prop, _copy(sub["default"]))
        yield from validate_properties(validator, properties, instance, sch)

    return jsonschema.validators.extend(validator_class, {"properties": set_defaults})


def _copy(value):
    return yaml.safe_load(yaml.safe_dump(value))


def validate_config(config: dict[str, Any], source: str | None = None) -> dict[str, Any]:
    """Validate ``config`` in place, filling defaults; raise :class:`ConfigError`.

    Examples
    --------
    >>> cfg = validate_config({"seed": 1})
    >>> cfg["cities_dir"]
    'config/cities'
    """
    validator = _with_defaults(jsonschema.Draft202012Validator)(schema())
    if not isinstance(config, dict):
        raise ConfigError(f"the configuration must be a mapping, not a {type(config).__name__}",
                          source=source, element="(top level)")
    bad = next((k for k in _keys(config) if not isinstance(k, str)), None)
    if bad is not None:  # YAML allows any key; the schema's patterns and names need text
        raise ConfigError(f"keys must be text, got {bad!r}"[:200], source=source,
                          element="(top level)")
    errors = sorted(validator.iter_errors(config), key=lambda e: [
        (0, x, "") if isinstance(x, int) else (1, 0, str(x)) for x in e.absolute_path])
    if errors:
        err = errors[0]
        element = ".".join(map(str, err.absolute_path)) or "(top level)"
        message = (err.message.splitlines() or ["invalid"])[0]
        raise ConfigError(message if len(message) <= 300 else message[:300] + "...",
                          source=source, element=element[:200])
    return config


def _keys(doc: Any):
    """Every mapping key anywhere in ``doc`` (iteratively: no recursion limit)."""
    stack = [doc]
    while stack:
        obj = stack.pop()
        if isinstance(obj, dict):
            yield from obj.keys()
            stack.extend(obj.values())
        elif isinstance(obj, list):
            stack.extend(obj)


def load_config(path: str | os.PathLike | None = None) -> dict[str, Any]:
    """Read and validate a config file (default ``config/config.yaml`` if present)."""
    p = Path(path) if path else DEFAULT_CONFIG
    if path is None and not p.exists():
        return validate_config({"seed": 20231024})
    doc = load_yaml(p, error=ConfigError)
    if doc is None:  # an empty file: every default
        doc = {}
    return validate_config(doc, str(p))
