"""The geometry package as a newcomer reads it: each module opens with what it decides
and what it reads, and no class grows past about 200 lines (issue 18)."""

import ast
from pathlib import Path

import pytest

GEOMETRY = Path(__file__).resolve().parent.parent / "flyover" / "geometry"
#: about 200 lines: a class past this is split by the concept it holds
MAX_CLASS_LINES = 210


def _modules():
    return sorted(p for p in GEOMETRY.glob("*.py") if p.name != "__init__.py")


@pytest.mark.parametrize("path", _modules(), ids=lambda p: p.name)
def test_each_geometry_module_opens_with_what_it_decides(path):
    doc = ast.get_docstring(ast.parse(path.read_text()))
    assert doc and len(doc.split()) >= 8, f"{path.name}: no docstring saying what it decides"


def test_no_geometry_class_is_over_about_200_lines():
    long = {f"{p.name}:{n.name}": n.end_lineno - n.lineno + 1
            for p in _modules() for n in ast.walk(ast.parse(p.read_text()))
            if isinstance(n, ast.ClassDef) and n.end_lineno - n.lineno + 1 > MAX_CLASS_LINES}
    assert long == {}
