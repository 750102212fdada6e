"""CommonRoad's map verifier (every formula but the two of ``LEFT_OUT_IN_CI``) on every other
catalog design (feature set 0) starting from the second; ``test_clients_verifier_0.py`` has
the rest. Two files so that ``--dist loadfile`` can run them on two workers."""

from __future__ import annotations

import pytest

from tests.clients_support import LEFT_OUT_IN_CI, check_verifier, clients_python, \
    verifier_designs  # noqa: F401


@pytest.mark.slow
@pytest.mark.parametrize("name", verifier_designs(1))
def test_commonroad_verifier_errors_are_the_conversions_not_our_geometry(tmp_path, clients_python,
                                                                         name):
    check_verifier(tmp_path, clients_python, name, 0, exclude=LEFT_OUT_IN_CI)
