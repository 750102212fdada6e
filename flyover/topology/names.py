"""Names that become file or folder names: the safe set, checks and a safe mapping.

An interchange's name becomes ``results/topology/{city}/{interchange}.graphml``
(and ``.png``), a city's name becomes ``results/topology/{city}/``. Such a name
must be a **safe name**:

* only ASCII letters, digits, ``.``, ``_`` and ``-``;
* starting with a letter or digit (so never ``.``, ``..`` or a hidden file);
* at most :data:`MAX_NAME_LENGTH` (100) characters.

Names a person writes (a YAML spec's ``name:``, a GraphML graph name, a file
name, a city folder) are checked with :func:`check_name`, which raises a
one-line :class:`~flyover.errors.UnsafeNameError` naming the file and the name.
Names made from data (OpenStreetMap ``ref`` tags such as ``"I 70;US 40"`` or
``"A 1/E 20"``) are mapped with :func:`safe_name` to a safe, stable form.

Examples
--------
>>> is_safe_name("cloverleaf_cd"), is_safe_name("../x"), is_safe_name(".hidden")
(True, False, False)
>>> safe_name("I 70;US 40")
'I-70-US-40'
>>> safe_name("Straße/B 2")
'Strasse-B-2'
"""

from __future__ import annotations

import hashlib
import re
import unicodedata
from pathlib import Path

from flyover.errors import UnsafeNameError

__all__ = ["MAX_NAME_LENGTH", "SAFE_NAME_RULE", "is_safe_name", "check_name", "safe_name",
           "child_path"]

#: longest safe name (file systems allow 255 bytes; room is left for suffixes and temp files)
MAX_NAME_LENGTH = 100

#: the rule, as error messages and the README state it
SAFE_NAME_RULE = (f"1-{MAX_NAME_LENGTH} characters from A-Z a-z 0-9 . _ -, "
                  "starting with a letter or digit")

_SAFE = re.compile(r"[A-Za-z0-9][A-Za-z0-9._-]*\Z")
_UNSAFE_RUN = re.compile(r"[^A-Za-z0-9._-]+")
_TRANSLITERATE = str.maketrans({"ß": "ss", "æ": "ae", "Æ": "AE", "ø": "o", "Ø": "O", "đ": "d",
                                "Đ": "D", "ł": "l", "Ł": "L", "œ": "oe", "Œ": "OE", "þ": "th"})


def is_safe_name(name: object) -> bool:
    """True when ``name`` is a string that is a safe name (see the module docstring)."""
    return isinstance(name, str) and len(name) <= MAX_NAME_LENGTH and bool(_SAFE.match(name))


def check_name(name: object, *, source: str | None = None, what: str = "interchange name") -> str:
    """Return ``name`` when it is a safe name, else raise.

    Parameters
    ----------
    name
        The name that will become a file or folder name.
    source
        The file it comes from (named in the error).
    what
        What the name is, for the message (``"interchange name"``, ``"city name"``).

    Raises
    ------
    UnsafeNameError
        One line: ``{source}: {name!r}: unsafe {what}: ...``.

    Examples
    --------
    >>> check_name("trumpet")
    'trumpet'
    >>> check_name("../../etc/x", source="city/a.yaml")
    Traceback (most recent call last):
    ...
    flyover.errors.UnsafeNameError: city/a.yaml: '../../etc/x': unsafe interchange name ...
    """
    if is_safe_name(name):
        return name  # type: ignore[return-value]
    shown = repr(name) if len(repr(name)) <= 2 * MAX_NAME_LENGTH else repr(name)[:2 * MAX_NAME_LENGTH] + "..."
    raise UnsafeNameError(f"unsafe {what} (it becomes a file name): use {SAFE_NAME_RULE}",
                          source=source, element=shown)


def safe_name(text: str, max_length: int = MAX_NAME_LENGTH) -> str:
    """Map any text to a safe name, stably (the same text always gives the same name).

    Letters with accents lose them (``é`` → ``e``, ``ß`` → ``ss``), every run of
    other unsafe characters becomes one ``-``, leading and trailing ``.``/``-``/``_``
    go. A result longer than ``max_length`` is cut and ends in ``-`` and 10 hex
    digits of a hash of ``text``; an empty result is ``x`` and that hash.

    Examples
    --------
    >>> safe_name("A 9")
    'A-9'
    >>> safe_name("..")[:2], len(safe_name("é" * 300)), safe_name("é" * 300)[-11:-10]
    ('x-', 100, '-')
    """
    digest = hashlib.sha1(text.encode("utf-8", "surrogatepass")).hexdigest()[:10]
    ascii_ = unicodedata.normalize("NFKD", text.translate(_TRANSLITERATE))
    ascii_ = ascii_.encode("ascii", "ignore").decode("ascii")
    out = _UNSAFE_RUN.sub("-", ascii_).strip("._-")
    if not out:
        return f"x-{digest}"
    if len(out) > max_length:
        out = out[:max_length - 11].rstrip("._-") + f"-{digest}"
    return out


def child_path(folder: str | Path, name: str, suffix: str = "", *, source: str | None = None,
               what: str = "interchange name") -> Path:
    """``folder / (name + suffix)`` after checking that ``name`` is safe.

    The one way flyover builds an output path from a name: the name is checked
    with :func:`check_name`, and the result is verified to lie directly in
    ``folder``.

    Raises
    ------
    UnsafeNameError
        ``name`` is not a safe name.
    """
    check_name(name, source=source, what=what)
    folder = Path(folder)
    path = folder / f"{name}{suffix}"
    if path.parent != folder:  # unreachable for a safe name; a second line of defence
        raise UnsafeNameError("name leaves its folder", source=source, element=repr(name))
    return path
