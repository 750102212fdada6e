"""The cluster tests are opt-in: they run only when `-m` names the `slurm` marker."""

from __future__ import annotations

import re

import pytest


def pytest_collection_modifyitems(config, items):
    markexpr = config.getoption("markexpr") or ""
    if re.search(r"(?<!not )\bslurm\b", markexpr):
        return
    skip = pytest.mark.skip(reason="opt-in: brings up a Slurm on this machine; run with -m slurm")
    for item in items:
        if item.get_closest_marker("slurm"):
            item.add_marker(skip)
