"""Fuzzing the OpenDRIVE reader (``flyover/opendrive/reader.py``, issue 19).

Seeds are the .xodr files our writer makes of the sample interchanges
(``flyover.opendrive.samples``), written in the test. Mutations: attribute values
swapped for hostile ones (``nan``, ``1e309``, text, paths), lines dropped,
duplicated or swapped, XML tricks (external entities, entity expansion, DTDs)
pasted in, the file cut short. Each either loads (and then its 3D continuity can
be measured, as ``flyover validate`` does) or raises a FlyoverError naming the file.
"""

from __future__ import annotations

import re

import pytest
from hypothesis import given
from hypothesis import strategies as st

from flyover.errors import FlyoverError, InputFormatError
from flyover.opendrive.continuity import check_continuity
from flyover.opendrive.reader import read_xodr
from flyover.opendrive.samples import SAMPLES, sample_geometry
from flyover.opendrive.writer import xodr_bytes
from tests.fuzz_support import FUZZ, assert_names_file, loads_or_names_file, mutated_xml, sandbox, write_text

SEEDS = [xodr_bytes(sample_geometry(kind)).decode() for kind in SAMPLES]
WORDS = ["line", "arc", "spiral", "poly3", "paramPoly3", "normalized", "arcLength", "road", "junction",
         "start", "end", "predecessor", "successor", "-1", "1", "0", "-2", "2", "driving", "none", "1.7",
         "1.8", "0.0", "1e-12", "1e12", "-1e12"]


def _read_and_measure(path):
    net = read_xodr(path)
    ok, detail = check_continuity(net)
    assert isinstance(ok, bool) and isinstance(detail, str)
    return net


@FUZZ
@given(text=st.sampled_from(SEEDS).flatmap(lambda s: mutated_xml(s, WORDS)))
def test_fuzz_opendrive_reader_loads_or_names_the_file(text):
    with sandbox() as root:
        loads_or_names_file(_read_and_measure, write_text(root / "in.xodr", text))


# -- what the fuzzers found, kept as plain regression tests ----------------------------------

@pytest.mark.parametrize("pattern, new, reason", [
    (r'revMajor="[^"]*"', 'revMajor="x"', "malformed header version"),
    (r'<laneLink from="[^"]*"', '<laneLink from="x"', "malformed junction"),
    (r'hdg="[^"]*"', 'hdg="nan"', "hdg='nan' is not a finite number"),
    (r'curvature="[^"]*"', 'curvature="-inf"', "is not a finite number"),
])
def test_malformed_values_are_one_line_errors_naming_the_file(tmp_path, pattern, new, reason):
    text = next(s for s in SEEDS + [_ARC] if re.search(pattern, s))
    path = write_text(tmp_path / "bad.xodr", re.sub(pattern, new, text, count=1))
    with pytest.raises(InputFormatError, match=reason) as info:
        read_xodr(path)
    assert_names_file(info.value, path)


_ARC = """<OpenDRIVE><header revMajor="1" revMinor="7"/>
<road id="1" length="10" junction="-1"><planView>
<geometry s="0" x="0" y="0" hdg="0" length="10"><arc curvature="0.01"/></geometry></planView>
<lanes><laneSection s="0"><center><lane id="0" type="none"/></center>
<right><lane id="-1" type="driving"><width sOffset="0" a="3.5" b="0" c="0" d="0"/></lane>
</right></laneSection></lanes></road></OpenDRIVE>
"""


def test_external_entities_are_not_read(tmp_path):
    secret = tmp_path / "secret.txt"
    secret.write_text("TOPSECRET")
    text = SEEDS[0].replace("<OpenDRIVE", f'<!DOCTYPE OpenDRIVE [<!ENTITY e SYSTEM "file://{secret}">]>'
                            "\n<OpenDRIVE", 1).replace('name="', 'name="&e;', 1)
    path = write_text(tmp_path / "xxe.xodr", text)
    try:
        net = read_xodr(path)
    except FlyoverError as exc:
        assert_names_file(exc, path)
        return
    assert not any("TOPSECRET" in r.name for r in net.roads.values())


def test_entity_expansion_bomb_is_not_expanded(tmp_path):
    ents = '<!ENTITY a0 "xxxxxxxxxx">' + "".join(
        f'<!ENTITY a{i} "{("&a%d;" % (i - 1)) * 10}">' for i in range(1, 10))
    text = SEEDS[0].replace("<OpenDRIVE", f"<!DOCTYPE OpenDRIVE [{ents}]>\n<OpenDRIVE", 1)
    text = text.replace('name="', 'name="&a9;', 1)
    path = write_text(tmp_path / "bomb.xodr", text)
    try:
        net = loads_or_names_file(read_xodr, path)
    except FlyoverError as exc:  # pragma: no cover - refusing is as good as not expanding
        assert_names_file(exc, path)
        return
    assert net is None or all(len(r.name) < 1000 for r in net.roads.values())
