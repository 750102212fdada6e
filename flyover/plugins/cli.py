"""``flyover plugins``: list the installed evaluation plugins."""

from __future__ import annotations

import argparse

__all__ = ["register"]


def register(subparsers: argparse._SubParsersAction) -> None:
    p = subparsers.add_parser(
        "plugins", help="list installed evaluation plugins (name, version, table)",
        description="List the plugins registered under the entry-point group flyover.plugins; "
                    "a plugin that cannot be loaded is listed as broken, with the reason.")
    p.set_defaults(func=_list)


def _list(args: argparse.Namespace) -> int:
    from flyover.plugins.api import PluginError  # noqa: PLC0415
    from flyover.plugins.registry import load_plugin, plugin_entry_points  # noqa: PLC0415

    infos = plugin_entry_points()
    if not infos:
        print("no plugins installed (entry-point group flyover.plugins)")
        return 0
    rows, broken = [("name", "version", "table", "distribution")], 0
    for info in infos:
        try:
            plugin = load_plugin(info.name)
            rows.append((info.name, plugin.version, plugin.table, info.distribution))
        except PluginError as exc:
            broken += 1
            rows.append((info.name, "BROKEN", exc.reason, info.distribution))
    widths = [max(len(r[i]) for r in rows) for i in range(3)]
    for r in rows:
        print("  ".join(c.ljust(w) for c, w in zip(r[:3], widths)) + "  " + r[3])
    return 1 if broken else 0
