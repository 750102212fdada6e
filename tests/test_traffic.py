"""Throughput experiment: stable windows, settings, demand, statistics (no SUMO run here)."""

from __future__ import annotations

import math

import numpy as np
import pytest

from flyover.config import load_config, validate_config
from flyover.errors import ConfigError
from flyover.traffic.batch import select_samples
from flyover.traffic.demand import Flow, routes_xml
from flyover.traffic.measure import stable_window
from flyover.traffic.settings import Arrivals, DepartLane, ThroughputSettings, run_seed
from flyover.traffic.stats import throughput_stats, welch
from tests.conftest import REPO


def _synthetic(rate_veh_h, travel_intervals, n=66, interval_s=30.0, seed=0, fill=1.0):
    """Poisson arrivals at ``rate``; each vehicle leaves ``travel_intervals`` later (x fill)."""
    rng = np.random.default_rng(seed)
    entered = rng.poisson(rate_veh_h * interval_s / 3600.0, n)
    left = np.zeros(n, dtype=int)
    for i, k in enumerate(entered):
        j = i + travel_intervals
        if j < n:
            left[j] += int(round(k * fill))
    return entered, left


@pytest.mark.parametrize("seed", range(8))
def test_stable_window_starts_after_the_network_has_filled(seed):
    entered, left = _synthetic(5400, travel_intervals=5, seed=seed)
    w = stable_window(entered, left, 30.0)
    # vehicles first leave after 5 intervals (150 s); the window starts around there
    assert 120.0 <= w.stable_from_s <= 330.0
    assert w.balanced
    assert w.throughput_veh_h == pytest.approx(5400, rel=0.06)
    assert len(w.per_interval_veh_h) == 66 - w.start


def test_a_network_that_keeps_filling_is_not_balanced():
    # only 70 % of what enters ever leaves: a growing jam
    entered, left = _synthetic(5400, travel_intervals=5, fill=0.7)
    w = stable_window(entered, left, 30.0)
    assert not w.balanced
    assert w.throughput_veh_h < 0.8 * w.entering_veh_h


def test_an_empty_run_has_zero_throughput_and_is_balanced():
    w = stable_window(np.zeros(40, int), np.zeros(40, int), 30.0)
    assert w.stable_from_s == 0.0 and w.throughput_veh_h == 0.0 and w.balanced


def test_a_window_shorter_than_the_minimum_is_not_balanced():
    entered, left = _synthetic(3600, travel_intervals=2, n=20)
    assert not stable_window(entered, left, 30.0, min_stable_s=500.0).balanced
    assert stable_window(entered, left, 30.0, min_stable_s=100.0).balanced


def test_settings_from_the_repository_configs():
    s = ThroughputSettings.from_config(load_config(REPO / "config" / "config.yaml"))
    assert s.densities == (450.0, 900.0, 1350.0, 1800.0) and s.duration_s == 2000.0
    assert s.uturns is False and s.depart_lane is DepartLane.FREE
    paper = ThroughputSettings.from_config(load_config(REPO / "config" / "paper.yaml"))
    assert paper.samples_per_class == 20 and paper.seed == s.seed


@pytest.mark.parametrize("section, element", [
    ({"densities": []}, "throughput.densities"),
    ({"depart_lane": "first"}, "throughput.depart_lane"),
    ({"speed": 3}, "throughput"),
])
def test_bad_throughput_config_names_the_key(section, element):
    with pytest.raises(ConfigError) as info:
        validate_config({"seed": 1, "throughput": section})
    assert info.value.element == element


def test_interval_must_divide_into_steps_and_the_run_into_intervals():
    with pytest.raises(ConfigError):
        ThroughputSettings(step_length_s=0.7, interval_s=30.0)
    with pytest.raises(ConfigError):
        ThroughputSettings(duration_s=2000.0, interval_s=30.0)  # 66.7 intervals
    assert ThroughputSettings(duration_s=2000.0, interval_s=20.0).interval_s == 20.0


def test_seeds_differ_per_run_and_repeat():
    seeds = {run_seed(1, "c0", s, d) for s in range(5) for d in (450, 900)}
    assert len(seeds) == 10
    assert run_seed(1, "c0", 3, 900) == run_seed(1, "c0", 3, 900.0)
    assert run_seed(2, "c0", 3, 900) != run_seed(1, "c0", 3, 900)


def test_sample_selection_is_seeded_and_a_subset():
    a = select_samples(range(64), 5, 7, "c1")
    assert a == select_samples(list(range(64))[::-1], 5, 7, "c1")
    assert len(set(a)) == 5 and set(a) <= set(range(64))
    assert a != select_samples(range(64), 5, 8, "c1")
    assert select_samples([3, 1, 2], 0, 7, "c1") == [1, 2, 3]
    assert select_samples([3, 1, 2], 5, 7, "c1") == [1, 2, 3]


def test_routes_file_has_one_flow_per_movement():
    flows = [Flow("A1->A1", ("-1", "-2")), Flow("A1->B1", ("-1", "-5", "-7"))]
    s = ThroughputSettings(duration_s=600.0)
    xml = routes_xml(flows, 900, s)
    assert xml.count("<flow ") == 2 and xml.count("<route ") == 2
    assert 'period="exp(0.25)"' in xml and 'end="600.0"' in xml
    assert 'departLane="free"' in xml and 'departSpeed="max"' in xml
    assert 'name="A1-&gt;B1"' in xml and 'edges="-1 -5 -7"' in xml
    uni = routes_xml(flows, 900, ThroughputSettings(arrivals=Arrivals.UNIFORM))
    assert 'vehsPerHour="900.0"' in uni


def test_welch_is_nan_without_two_values_or_spread():
    assert all(math.isnan(x) for x in welch([1.0], [2.0, 3.0]))
    assert all(math.isnan(x) for x in welch([1.0, 1.0], [1.0, 1.0]))
    t, p = welch([10.0, 11.0, 12.0, 10.5], [20.0, 21.0, 19.0, 20.5])
    assert t < 0 and p < 1e-3


def _rows():
    rows = []
    for c, base in (("ca", 1000.0), ("cb", 2000.0), ("cc", 2010.0)):
        for s in range(3):
            rows.append({"class_id": c, "sample": s, "density_veh_h": 450.0, "ok": True,
                         "throughput_veh_h": base + 10.0 * s, "stable_from_s": 60.0,
                         "flagged": c == "cc" and s == 0})
    rows.append({"class_id": "cc", "sample": 9, "density_veh_h": 450.0, "ok": False,
                 "throughput_veh_h": float("nan"), "stable_from_s": float("nan"),
                 "flagged": False})
    series = [{"class_id": r["class_id"], "sample": r["sample"], "density_veh_h": 450.0,
               "t_s": 30.0 * i, "left": int(r["throughput_veh_h"] / 120) + (i % 3)}
              for r in rows if r["ok"] for i in range(20)]
    return rows, series


def test_stats_tests_every_pair_and_reports_table_iii():
    rows, series = _rows()
    st = throughput_stats(rows, series)
    cls = [r for r in st if r["scope"] == "class"]
    assert {(r["a"], r["b"]) for r in cls} == {("ca", "cb"), ("ca", "cc"), ("cb", "cc")}
    ab = next(r for r in cls if (r["a"], r["b"]) == ("ca", "cb"))
    assert ab["p_value"] < 1e-4 and ab["n_a"] == ab["n_b"] == 3
    bc = next(r for r in cls if (r["a"], r["b"]) == ("cb", "cc"))
    assert bc["p_value"] > 0.2 and bc["n_flagged_b"] == 1  # the failed run is left out
    samples = [r for r in st if r["scope"] == "sample"]
    assert len(samples) == 3 * 3  # 3 pairs in each of 3 classes
    assert all(r["n_a"] == 18 for r in samples)  # intervals from 60 s on
    inter = next(r for r in st if r["scope"] == "inter_class_std")
    means = [1010.0, 2010.0, 2020.0]
    assert inter["std_veh_h"] == pytest.approx(np.std(means, ddof=1))
    intra = {r["a"]: r["std_veh_h"] for r in st if r["scope"] == "intra_class_std"}
    assert intra["ca"] == pytest.approx(10.0) and intra["*"] == pytest.approx(10.0)
    assert inter["std_veh_h"] > 20 * intra["*"]
