"""Evaluation plugins: discovery, the plugin contract and the batch runner.

A plugin is a separate distribution that registers an object under the
entry-point group ``flyover.plugins`` (see :mod:`flyover.plugins.api` for what
that object must provide). flyover never imports a plugin by name: it lists the
entry points (:func:`plugin_entry_points`, cheap: nothing is imported), loads
them on demand (:func:`load_plugin`, :func:`installed_plugins`) and skips a
broken one with a warning naming it.

:func:`run_plugins_on_class` evaluates many interchanges in one process and
writes hive-partitioned Parquet ``{results}/{table}/class_id=…/sample=…/part-0.parquet``.

The submodules are imported on first use so that ``flyover --help`` stays fast.
"""

from __future__ import annotations

import importlib
from typing import Any

__all__ = [
    "ENTRY_POINT_GROUP",
    "Plugin",
    "PluginError",
    "PluginInfo",
    "plugin_entry_points",
    "load_plugin",
    "installed_plugins",
    "plugin_config",
    "run_plugins_on_class",
    "write_partition",
    "ClassRun",
]

ENTRY_POINT_GROUP = "flyover.plugins"

_WHERE = {
    "Plugin": "flyover.plugins.api",
    "PluginError": "flyover.plugins.api",
    "plugin_config": "flyover.plugins.api",
    "PluginInfo": "flyover.plugins.registry",
    "plugin_entry_points": "flyover.plugins.registry",
    "load_plugin": "flyover.plugins.registry",
    "installed_plugins": "flyover.plugins.registry",
    "run_plugins_on_class": "flyover.plugins.batch",
    "write_partition": "flyover.plugins.batch",
    "ClassRun": "flyover.plugins.batch",
}


def __getattr__(name: str) -> Any:
    if name in _WHERE:
        return getattr(importlib.import_module(_WHERE[name]), name)
    raise AttributeError(f"module 'flyover.plugins' has no attribute {name!r}")
