"""Loading YAML written by anyone: one-line errors, bounded work.

:func:`yaml.safe_load` already refuses arbitrary objects, but a hostile or
broken file can still make it (or the code walking its result) fail in ways
that are not a :class:`yaml.YAMLError`: dates such as ``2023-13-45``
(``ValueError``), very deep nesting (``RecursionError``), bytes that are not
UTF-8, a recursive alias (``&a [*a]``), the YAML "billion laughs" (aliases
of aliases that expand to an exponential number of values) and flow brackets
nested thousands deep (PyYAML's scanner is quadratic in the depth). :func:`load_yaml`
turns every one of these into the caller's :class:`~flyover.errors.FlyoverError`
naming the file.

Example
-------
>>> import tempfile, pathlib
>>> with tempfile.TemporaryDirectory() as d:
...     p = pathlib.Path(d, "x.yaml")
...     _ = p.write_text("a: &a [1, 2]\\nb: [*a, *a]\\n")
...     load_yaml(p)
{'a': [1, 2], 'b': [[1, 2], [1, 2]]}
"""

from __future__ import annotations

import os
import re
from pathlib import Path
from typing import Any

import yaml

from flyover.errors import FlyoverError, InputFormatError

__all__ = ["MAX_YAML_VALUES", "MAX_FLOW_DEPTH", "load_yaml"]

#: most values (scalars, lists, mappings) a document may expand to, aliases counted each time used
MAX_YAML_VALUES = 1_000_000

#: deepest nesting of ``[`` / ``{`` (PyYAML's scanner takes time quadratic in it: 3000 levels took 7 s)
MAX_FLOW_DEPTH = 100

_BRACKETS = re.compile(r"[\[\]{}]")


def _flow_depth(text: str) -> int:
    """Deepest nesting of flow brackets in ``text`` (brackets in quotes and comments are
    counted too: an upper bound)."""
    depth = deepest = 0
    for m in _BRACKETS.finditer(text):
        depth = depth + 1 if m.group() in "[{" else max(depth - 1, 0)
        deepest = max(deepest, depth)
    return deepest


def _expanded_size(doc: Any, limit: int) -> int:
    """Number of values ``doc`` holds with every alias expanded (shared objects counted each
    time they are used), in time linear in the distinct objects; stops counting past ``limit``.

    Raises ``ValueError`` for a recursive structure.
    """
    sizes: dict[int, int] = {}
    active: set[int] = set()
    keep: list[Any] = []  # keep the objects alive while their ids are keys
    stack: list[tuple[Any, bool]] = [(doc, False)]
    while stack:
        obj, done = stack.pop()
        if not isinstance(obj, (list, dict)):
            continue
        key = id(obj)
        if done:
            children = list(obj.values()) + list(obj.keys()) if isinstance(obj, dict) else obj
            total = 1
            for c in children:
                total += sizes.get(id(c), 1) if isinstance(c, (list, dict)) else 1
            sizes[key] = min(total, limit + 1)
            active.discard(key)
            continue
        if key in sizes:
            continue
        if key in active:
            raise ValueError("recursive alias (a value contains itself)")
        active.add(key)
        keep.append(obj)
        stack.append((obj, True))
        children = list(obj.values()) + list(obj.keys()) if isinstance(obj, dict) else obj
        for c in children:
            if isinstance(c, (list, dict)):
                if id(c) in active:
                    raise ValueError("recursive alias (a value contains itself)")
                stack.append((c, False))
    return sizes.get(id(doc), 1)


def load_yaml(path: str | os.PathLike, *, error: type[FlyoverError] = InputFormatError,
              max_values: int = MAX_YAML_VALUES) -> Any:
    """Parse the YAML file at ``path`` safely.

    Parameters
    ----------
    path
        The file.
    error
        The :class:`~flyover.errors.FlyoverError` subclass to raise.
    max_values
        Largest number of values the document may expand to (aliases counted
        each time used).

    Raises
    ------
    FlyoverError
        (``error``) naming the file: unreadable, not UTF-8, malformed YAML (with its
        line), a value YAML cannot construct, nested too deeply, a recursive alias,
        or too large once its aliases are expanded.
    """
    src = str(path)
    try:
        text = Path(path).read_text(encoding="utf-8")
    except UnicodeDecodeError as exc:
        raise error(f"not UTF-8 text (byte {exc.start})", source=src) from None
    except OSError as exc:
        raise error(f"cannot read: {exc.strerror or exc}", source=src) from None
    if _flow_depth(text) > MAX_FLOW_DEPTH:
        raise error(f"malformed YAML: [ ] or {{ }} nested more than {MAX_FLOW_DEPTH} deep", source=src)
    try:
        doc = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        mark = getattr(exc, "problem_mark", None)
        where = f" (line {mark.line + 1})" if mark is not None else ""
        raise error(f"malformed YAML{where}: {str(exc).splitlines()[0]}", source=src) from None
    except RecursionError:
        raise error("malformed YAML: nested too deeply", source=src) from None
    except (ValueError, TypeError, OverflowError) as exc:  # e.g. a date 2023-13-45
        raise error(f"malformed YAML: {str(exc).splitlines()[0] if str(exc) else type(exc).__name__}",
                    source=src) from None
    try:
        size = _expanded_size(doc, max_values)
    except ValueError as exc:
        raise error(f"malformed YAML: {exc}", source=src) from None
    if size > max_values:
        raise error(f"YAML document expands to more than {max_values} values (aliases of aliases?)",
                    source=src)
    return doc
