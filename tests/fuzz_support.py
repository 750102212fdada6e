"""Shared pieces of the fuzz tests (``tests/test_fuzz_*.py``): settings, mutations, checks.

Every fuzz test states the same contract for one reader: a generated or mutated
input either loads or raises a :class:`~flyover.errors.FlyoverError` whose one
line names the file; never another exception, never a hang, and an import
writes nothing outside its output folder.

Runs
----
* default: ``FUZZ`` runs ``FUZZ_EXAMPLES`` (150) derandomized cases per test — the
  same cases every run, the whole fuzz suite in well under a minute on one core;
* long: ``FLYOVER_FUZZ=long`` (``FLYOVER_FUZZ_EXAMPLES=N``, default 3000) draws
  new random cases each run, e.g.
  ``FLYOVER_FUZZ=long .venv/bin/python -m pytest tests/test_fuzz_*.py
  --hypothesis-show-statistics``.

A case that takes longer than ``HANG_SECONDS`` fails as a hang (SIGALRM); the
hypothesis deadline flags cases slower than ``DEADLINE``.
"""

from __future__ import annotations

import contextlib
import copy
import os
import signal
import tempfile
from datetime import timedelta
from pathlib import Path
from typing import Callable, Iterator
from xml.sax.saxutils import escape

from hypothesis import HealthCheck, settings
from hypothesis import strategies as st

from flyover.errors import FlyoverError

LONG = os.environ.get("FLYOVER_FUZZ", "") == "long"
FUZZ_EXAMPLES = int(os.environ.get("FLYOVER_FUZZ_EXAMPLES", 3000 if LONG else 150))
HANG_SECONDS = 20
DEADLINE = timedelta(seconds=10)  # generous: the machine is shared; a hang is caught by HANG_SECONDS

#: hypothesis settings of every fuzz test (no example database: nothing is written to the repo)
FUZZ = settings(
    max_examples=FUZZ_EXAMPLES,
    deadline=DEADLINE,
    derandomize=not LONG,
    database=None,
    print_blob=True,
    suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large,
                           HealthCheck.function_scoped_fixture],
)


def fuzz(share: float) -> settings:
    """:data:`FUZZ` with ``share`` of its examples (for targets whose cases take longer)."""
    return settings(FUZZ, max_examples=max(10, int(FUZZ_EXAMPLES * share)))


class Hang(Exception):
    """A case ran longer than :data:`HANG_SECONDS`."""


@contextlib.contextmanager
def hard_timeout(seconds: float = HANG_SECONDS) -> Iterator[None]:
    """Fail a case that runs longer than ``seconds`` (the deadline only reports after the fact)."""
    def _alarm(signum, frame):
        raise Hang(f"no result after {seconds} s: a hang")

    old = signal.signal(signal.SIGALRM, _alarm)
    signal.setitimer(signal.ITIMER_REAL, seconds)
    try:
        yield
    finally:
        signal.setitimer(signal.ITIMER_REAL, 0)
        signal.signal(signal.SIGALRM, old)


def loads_or_names_file(read: Callable[[Path], object], path: Path) -> object | None:
    """Call ``read(path)``: return its result, or ``None`` after checking that the
    :class:`FlyoverError` it raised names ``path`` on one line. Any other exception fails."""
    with hard_timeout():
        try:
            return read(path)
        except FlyoverError as exc:
            assert_names_file(exc, path)
            return None


def assert_names_file(exc: FlyoverError, path: Path | str) -> None:
    """``exc`` is one line that starts with ``path``."""
    text = str(exc)
    assert exc.source == str(path), f"error does not name the file: {text!r}"
    assert text.startswith(f"{path}: "), text
    assert "\n" not in text and "\r" not in text, f"not one line: {text!r}"


def files_under(root: Path) -> set[Path]:
    """Every file and folder under ``root``."""
    return {p for p in root.rglob("*")}


@contextlib.contextmanager
def sandbox() -> Iterator[Path]:
    """A fresh temporary folder, also the working directory while inside."""
    cwd = os.getcwd()
    with tempfile.TemporaryDirectory(prefix="flyover-fuzz-") as tmp:
        root = Path(tmp)
        os.chdir(root)
        try:
            yield root
        finally:
            os.chdir(cwd)


def import_stays_inside(files: list[Path], root: Path, city: str = "fuzzcity") -> dict:
    """Run the city import of ``files`` into ``root/deep/results/topology/{city}`` and check
    that it wrote nothing elsewhere under ``root`` (the working directory too), that every
    file it wrote has a safe name, and that each rejection names its file."""
    from flyover.topology.city import import_city
    from flyover.topology.names import is_safe_name

    out = root / "deep" / "er" / "results" / "topology" / city
    before = files_under(root)
    with hard_timeout():
        index = import_city(city, files, out)
    new = files_under(root) - before
    outside = sorted(str(p) for p in new if p != out and out not in p.parents and p not in out.parents)
    assert not outside, f"written outside {out}: {outside}"
    for p in out.iterdir():
        assert p.parent == out and p.is_file(), p
        assert is_safe_name(p.name) and not p.name.startswith("."), f"unsafe or temporary file left: {p.name!r}"
    for item in index["interchanges"]:
        assert Path(item["graphml"]).parent == out and is_safe_name(item["interchange"])
    sources = {str(f) for f in files}
    for rej in index["rejected"]:
        assert rej["source_file"] in sources and "\n" not in rej["reason"], rej
    return index


# -- values and mutations -------------------------------------------------------

#: text that has broken parsers before: numbers at the edges, names that are paths, controls
HOSTILE_WORDS = [
    "", " ", "0", "-0", "-1", "1", "2", "99999999999999999999", "1e309", "-1e309", "nan", "NaN",
    "inf", "-inf", "0.5", "1.5", "-0.5", "1,5", "0x10", "true", "yes", "no", "null", "~",
    "../../../../x", "..", ".", "/", "/tmp/x", "a/b", "a\\b", "C:\\x", "A 1;B 2", "A 1/E 20",
    "I 70;US 40", ";", ";;", "a b", "x" * 300, "Ω", "é", "日本", "\u202e", "\t", "\n",
    "\x7f", "&", "<", ">", "'", '"', "%s", "{0}", "*", "?", ":", "|", "CON", "NUL", "aux.txt",
]


def hostile_text(vocabulary: list[str] = ()) -> st.SearchStrategy[str]:
    """Domain words, hostile words, numbers and arbitrary text."""
    return st.one_of(
        st.sampled_from(list(vocabulary) or ["x"]),
        st.sampled_from(HOSTILE_WORDS),
        st.integers(-10**6, 10**6).map(str),
        st.floats(allow_nan=True, allow_infinity=True).map(repr),
        st.text(max_size=12),
    )


_XML_SNIPPETS = [
    "<", ">", "&", "&amp;", "&e;", "&#0;", "&#xFFFF;", "<!--", "-->", "<![CDATA[x]]>", "]]>",
    '<!DOCTYPE x [<!ENTITY e SYSTEM "file:///etc/passwd">]>',
    '<!DOCTYPE x [<!ENTITY a "aaaaaaaaaa"><!ENTITY b "&a;&a;&a;&a;&a;&a;&a;&a;&a;&a;">'
    '<!ENTITY c "&b;&b;&b;&b;&b;&b;&b;&b;&b;&b;"><!ENTITY d "&c;&c;&c;&c;&c;&c;&c;&c;&c;&c;">]>',
    "<?xml version='1.0' encoding='latin-1'?>", "\ufeff", "\x00", "\udcff",
]


def _values(text: str) -> list[tuple[int, int]]:
    """Spans of attribute values and element text in XML-ish ``text``."""
    import re

    spans = [(m.start(1), m.end(1)) for m in re.finditer(r'="([^"]*)"', text)]
    spans += [(m.start(1), m.end(1)) for m in re.finditer(r">([^<>]+)<", text) if m.group(1).strip()]
    return spans


@st.composite
def mutated_xml(draw, seed: str, vocabulary: list[str] = ()) -> str:
    """``seed`` with 1-6 mutations: values replaced by hostile ones (escaped or raw),
    lines deleted, duplicated or swapped, XML snippets inserted, the end cut off."""
    text = seed
    for _ in range(draw(st.integers(1, 6))):
        op = draw(st.sampled_from(["value", "value", "value", "raw_value", "delete_line",
                                   "dup_line", "swap_lines", "snippet", "truncate"]))
        lines = text.splitlines(keepends=True)
        if op in ("value", "raw_value"):
            spans = _values(text)
            if not spans:
                continue
            a, b = spans[draw(st.integers(0, len(spans) - 1))]
            new = draw(hostile_text(vocabulary))
            new = escape(new, {'"': "&quot;"}) if op == "value" else new
            text = text[:a] + new + text[b:]
        elif op == "delete_line" and len(lines) > 1:
            del lines[draw(st.integers(0, len(lines) - 1))]
            text = "".join(lines)
        elif op == "dup_line" and lines:
            i = draw(st.integers(0, len(lines) - 1))
            lines.insert(i, lines[i])
            text = "".join(lines)
        elif op == "swap_lines" and len(lines) > 1:
            i, j = draw(st.integers(0, len(lines) - 1)), draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
            text = "".join(lines)
        elif op == "snippet":
            i = draw(st.integers(0, len(text)))
            text = text[:i] + draw(st.sampled_from(_XML_SNIPPETS)) + text[i:]
        elif op == "truncate":
            text = text[:draw(st.integers(0, len(text)))]
    return text


def write_text(path: Path, text: str) -> Path:
    """Write ``text`` as UTF-8 (lone surrogates as they would come from broken bytes)."""
    path.write_bytes(text.encode("utf-8", "surrogatepass"))
    return path


# -- YAML -------------------------------------------------------------------------

#: YAML that has broken loaders: aliases, tags, dates, depth
YAML_SNIPPETS = [
    "a: &a [*a]\n", "x: &x {k: *x}\n",
    "l0: &l0 [x, x, x, x, x, x, x, x, x, x]\n" + "".join(
        f"l{i}: &l{i} [*l{i-1}, *l{i-1}, *l{i-1}, *l{i-1}, *l{i-1}, *l{i-1}, *l{i-1}, *l{i-1}]\n"
        for i in range(1, 9)),
    "!!python/object/apply:os.system ['touch pwned']\n", "x: !!python/name:os.system\n",
    "d: 2023-13-45\n", "d: 2023-02-30 25:61:61\n", "n: !!int x\n", "f: !!float abc\n",
    "b: !!binary '@@@'\n", "t: !!timestamp 2020-99-99\n", "s: !!set {a, b}\n", "? [a, b]\n: c\n",
    "[" * 3000 + "]" * 3000 + "\n", "{a: " * 3000 + "1" + "}" * 3000 + "\n",
    "<<: *undefined\n", "%YAML 1.1\n---\n", "---\n---\n", "\t- x\n", "key: 'unterminated\n",
    "big: " + "9" * 5000 + "\n", "\x00\n", "\ufeffname: x\n", "name: \udcff\n",
]

def json_values(words: list[str] = ()) -> st.SearchStrategy:
    """Any YAML data: null, booleans, numbers, hostile text, small lists and mappings."""
    return st.recursive(
        st.none() | st.booleans() | st.integers(-10**20, 10**20) | st.floats() | hostile_text(words),
        lambda inner: st.lists(inner, max_size=4) | st.dictionaries(hostile_text(words), inner, max_size=4),
        max_leaves=12,
    )


def _paths(doc, prefix=()):
    """Every (path, value) in a nested mapping/list."""
    yield prefix, doc
    if isinstance(doc, dict):
        for k, v in doc.items():
            yield from _paths(v, prefix + (k,))
    elif isinstance(doc, list):
        for i, v in enumerate(doc):
            yield from _paths(v, prefix + (i,))


@st.composite
def mutated_doc(draw, docs: list, words: list[str] = ()):
    """One of ``docs`` (parsed YAML) with 1-4 data mutations: a value replaced, a key
    deleted, added or renamed."""
    doc = copy.deepcopy(draw(st.sampled_from(docs)))
    for _ in range(draw(st.integers(1, 4))):
        paths = [p for p, _ in _paths(doc) if p]
        if not paths:
            break
        path = draw(st.sampled_from(paths))
        parent = doc
        for k in path[:-1]:
            parent = parent[k]
        op = draw(st.sampled_from(["replace", "replace", "delete", "add", "rename"]))
        if op == "rename" and isinstance(parent, dict):  # same value under a hostile key
            parent[draw(hostile_text(words))] = parent.pop(path[-1])
        elif op == "replace":
            parent[path[-1]] = draw(json_values(words))
        elif op == "delete":
            del parent[path[-1]]
        elif op == "add" and isinstance(parent, dict):
            parent[draw(hostile_text(words))] = draw(json_values(words))
    return doc


@st.composite
def mutated_yaml_text(draw, texts: list[str], words: list[str] = ()):
    """One of ``texts`` (YAML) with 1-4 text mutations: lines dropped, duplicated, swapped,
    edited, YAML tricks pasted in."""
    lines = draw(st.sampled_from(texts)).splitlines(keepends=True)
    for _ in range(draw(st.integers(1, 4))):
        op = draw(st.sampled_from(["delete", "dup", "swap", "snippet", "snippet", "edit"]))
        i = draw(st.integers(0, len(lines) - 1)) if lines else 0
        if op == "delete" and lines:
            del lines[i]
        elif op == "dup" and lines:
            lines.insert(i, lines[i])
        elif op == "swap" and lines:
            j = draw(st.integers(0, len(lines) - 1))
            lines[i], lines[j] = lines[j], lines[i]
        elif op == "snippet":
            lines.insert(i, draw(st.sampled_from(YAML_SNIPPETS)))
        elif op == "edit" and lines:
            line = lines[i]
            k = draw(st.integers(0, len(line)))
            lines[i] = line[:k] + draw(hostile_text(words)) + line[k:]
    return "".join(lines)
