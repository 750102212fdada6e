"""Exceptions raised by flyover, each carrying the file and element at fault."""

from __future__ import annotations

__all__ = ["FlyoverError", "TopologyError", "InputFormatError", "ConfigError", "UnsafeNameError"]


def _printable(text: str) -> str:
    """``text`` with control characters (line breaks, tabs, NUL ...) escaped as in ``repr``."""
    if text.isprintable():
        return text
    return "".join(ch if ch.isprintable() else repr(ch)[1:-1] for ch in text)


class FlyoverError(Exception):
    """Base class: a problem with a user-supplied input.

    Parameters
    ----------
    reason
        What rule was broken, in one line.
    source
        The file the problem was found in (``None`` when built in memory).
    element
        The node, edge or key at fault, e.g. ``"r3"`` or ``"A1->r2"``.
    """

    def __init__(self, reason: str, *, source: str | None = None, element: str | None = None):
        # text from the data may hold line breaks: reason and element stay one line
        # wherever they are shown (console, rejected.parquet, index.json)
        self.reason = _printable(str(reason))
        self.source = source
        self.element = None if element is None else _printable(str(element))
        super().__init__(self.one_line())

    def one_line(self) -> str:
        """``{source}: {element}: {reason}`` on one line (line breaks and other control
        characters from the data are shown escaped, e.g. ``\\n``)."""
        where = _printable(self.source or "<memory>")
        if self.element:
            where += f": {self.element}"
        return f"{where}: {self.reason}"

    def located(self, source: str) -> "FlyoverError":
        """Return the same error attributed to ``source`` if it had none."""
        if self.source is None:
            self.source = source
            self.args = (self.one_line(),)
        return self


class TopologyError(FlyoverError):
    """A topology breaks a rule of the model (paper Def. 1)."""


class InputFormatError(FlyoverError):
    """A file cannot be read: malformed XML/YAML or an unknown schema."""


class ConfigError(FlyoverError):
    """The workflow configuration fails its schema."""


class UnsafeNameError(InputFormatError):
    """A name that would become a file or folder name is not a safe name
    (:mod:`flyover.topology.names`: ASCII letters, digits, ``. _ -``, at most 100)."""
