"""Finding installed plugins through the entry-point group ``flyover.plugins``.

Listing (:func:`plugin_entry_points`) reads distribution metadata only; a
plugin's code is imported when it is loaded (:func:`load_plugin`). A plugin
that fails to import, or whose object breaks the contract of
:mod:`flyover.plugins.api`, is skipped by :func:`installed_plugins` with a
warning naming it and the reason.
"""

from __future__ import annotations

import re

import logging
from dataclasses import dataclass
from importlib import metadata
from typing import Any

from flyover.plugins.api import REQUIRED_ATTRIBUTES, PluginError

__all__ = ["PluginInfo", "plugin_entry_points", "load_plugin", "installed_plugins"]

log = logging.getLogger(__name__)

GROUP = "flyover.plugins"


@dataclass(frozen=True)
class PluginInfo:
    """An entry point of the group, before anything is imported.

    Attributes
    ----------
    name
        The entry point's name (the plugin's name).
    value
        ``module:attribute`` it points to.
    distribution, distribution_version
        The installed distribution that registers it (empty when unknown).
    """

    name: str
    value: str
    distribution: str = ""
    distribution_version: str = ""


def _entry_points() -> dict[str, metadata.EntryPoint]:
    eps = {}
    for ep in metadata.entry_points(group=GROUP):
        if ep.name in eps:
            log.warning("plugin %s is registered twice (%s and %s); using the first",
                        ep.name, eps[ep.name].value, ep.value)
            continue
        eps[ep.name] = ep
    return eps


def plugin_entry_points() -> tuple[PluginInfo, ...]:
    """Every entry point of the group ``flyover.plugins``, sorted by name (nothing imported)."""
    out = []
    for name, ep in sorted(_entry_points().items()):
        dist = getattr(ep, "dist", None)
        out.append(PluginInfo(name, ep.value, dist.name if dist else "",
                              dist.version if dist else ""))
    return tuple(out)


def _check(obj: Any, name: str) -> Any:
    missing = [a for a in REQUIRED_ATTRIBUTES if not hasattr(obj, a)]
    if missing:
        raise PluginError(f"plugin object lacks {', '.join(missing)}", element=name)
    if obj.name != name:
        raise PluginError(f"plugin calls itself {obj.name!r} but is registered as {name!r}",
                          element=name)
    for attr in ("version", "table"):
        if not isinstance(getattr(obj, attr), str) or not getattr(obj, attr):
            raise PluginError(f"plugin {attr} must be a non-empty string", element=name)
    if not re.fullmatch(r"[a-z][a-z0-9_]{0,63}", obj.table):  # it becomes results/{table}/
        raise PluginError(f"plugin table {obj.table!r} must be a safe name "
                          "(lower-case letters, digits, _; it becomes a folder)", element=name)
    return obj


def load_plugin(name: str) -> Any:
    """Import and instantiate the plugin registered as ``name``.

    Raises
    ------
    PluginError
        When no plugin has that name, or it fails to import, instantiate or
        keep the contract (the message says which and why).
    """
    eps = _entry_points()
    if name not in eps:
        raise PluginError(f"no installed plugin of that name (installed: "
                          f"{', '.join(sorted(eps)) or 'none'})", element=name)
    try:
        obj = eps[name].load()
        if isinstance(obj, type) or (callable(obj) and not hasattr(obj, "evaluate")):
            obj = obj()
    except Exception as exc:  # noqa: BLE001 - any import-time error makes a plugin broken
        raise PluginError(f"cannot load {eps[name].value}: {type(exc).__name__}: {exc}",
                          element=name) from exc
    return _check(obj, name)


def installed_plugins(names: list[str] | tuple[str, ...] | None = None) -> dict[str, Any]:
    """Load the installed plugins (all, or those in ``names``), skipping broken ones.

    A broken plugin is logged as a warning naming it and the reason; the
    others are returned, keyed by name.
    """
    wanted = sorted(_entry_points()) if names is None else list(names)
    out = {}
    for name in wanted:
        try:
            out[name] = load_plugin(name)
        except PluginError as exc:
            log.warning("skipping broken plugin %s: %s", name, exc.reason)
    return out
