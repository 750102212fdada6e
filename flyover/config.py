"""Workflow configuration: loading and validation against the JSON schema."""

from __future__ import annotations

import os
from functools import lru_cache
from pathlib import Path
from typing import Any

import jsonschema
import yaml

from flyover.errors import ConfigError

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
    errors = sorted(validator.iter_errors(config), key=lambda e: list(e.absolute_path))
    if errors:
        err = errors[0]
        element = ".".join(map(str, err.absolute_path)) or "(top level)"
        raise ConfigError(err.message, source=source, element=element)
    return config


def load_config(path: str | os.PathLike | None = None) -> dict[str, Any]:
    """Read and validate a config file (default ``config/config.yaml`` if present)."""
    p = Path(path) if path else DEFAULT_CONFIG
    if path is None and not p.exists():
        return validate_config({"seed": 20231024})
    try:
        doc = yaml.safe_load(p.read_text(encoding="utf-8")) or {}
    except (OSError, yaml.YAMLError) as exc:
        raise ConfigError(f"cannot read config: {exc}", source=str(p)) from None
    return validate_config(doc, str(p))
