"""The plugin contract: what an object registered under ``flyover.plugins`` provides.

An entry point's object is either a plugin or a zero-argument callable (e.g. a
class) returning one. A plugin has

* ``name`` (``str``): equal to its entry point's name and to its config section
  under ``plugins:`` in ``config/config.yaml``;
* ``version`` (``str``): a rerun trigger of the workflow step;
* ``table`` (``str``): the results folder its rows go to (``results/{table}/``);
* ``config_schema()`` → a JSON schema (``dict``) of its config section, with
  ``default`` values;
* ``schema()`` → the :class:`pyarrow.Schema` of its rows; ``class_id`` and
  ``sample`` are among the columns (they become the hive partitions);
* ``evaluate(geometry, config)`` → the rows (``list`` of ``dict``) of one
  :class:`~flyover.geometry.model.InterchangeGeometry`;
* optionally ``failure_rows(class_id, sample, reason)`` → rows recording an
  interchange it could not evaluate at all (otherwise such a failure is only
  logged and counted).

Example
-------
>>> plugin_config({"type": "object", "properties": {"speed": {"type": "number",
...                "default": 10.0}}}, {}, plugin="demo")
{'speed': 10.0}
"""

from __future__ import annotations

import copy
from typing import Any, Mapping, Protocol, runtime_checkable

from flyover.errors import ConfigError, FlyoverError

__all__ = ["Plugin", "PluginError", "plugin_config", "REQUIRED_ATTRIBUTES"]

#: what :func:`flyover.plugins.registry.load_plugin` checks a loaded object has
REQUIRED_ATTRIBUTES = ("name", "version", "table", "config_schema", "schema", "evaluate")


class PluginError(FlyoverError):
    """A plugin cannot be loaded or does not keep the plugin contract."""


@runtime_checkable
class Plugin(Protocol):
    """Structural type of a plugin (see the module docstring)."""

    name: str
    version: str
    table: str

    def config_schema(self) -> Mapping[str, Any]: ...

    def schema(self) -> Any: ...

    def evaluate(self, geometry: Any, config: Mapping[str, Any]) -> list[dict[str, Any]]: ...


def _fill_defaults(schema: Mapping[str, Any], instance: Any) -> None:
    """Fill ``default`` values of ``properties`` into ``instance``, recursively."""
    if not isinstance(instance, dict):
        return
    for key, sub in (schema.get("properties") or {}).items():
        if key not in instance and "default" in sub:
            instance[key] = copy.deepcopy(sub["default"])
        if key in instance:
            _fill_defaults(sub, instance[key])


def plugin_config(schema: Mapping[str, Any], section: Mapping[str, Any] | None, *,
                  plugin: str, source: str | None = None) -> dict[str, Any]:
    """A plugin's config section, validated against its schema, defaults filled.

    Raises
    ------
    ConfigError
        Naming ``plugins.<plugin>.<key>`` when the section breaks the schema.
    """
    import jsonschema  # noqa: PLC0415

    cfg = copy.deepcopy(dict(section or {}))
    _fill_defaults(schema, cfg)
    validator = jsonschema.Draft202012Validator(schema)
    errors = sorted(validator.iter_errors(cfg), key=lambda e: list(e.absolute_path))
    if errors:
        err = errors[0]
        element = ".".join(["plugins", plugin, *map(str, err.absolute_path)])
        raise ConfigError(err.message, source=source, element=element)
    return cfg
