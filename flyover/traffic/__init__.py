"""Step 6: traffic throughput of concrete interchanges in SUMO (paper §IV-B).

* :mod:`~flyover.traffic.settings` — the ``throughput:`` config section, seeds;
* :mod:`~flyover.traffic.demand` — one flow per entrance → exit movement;
* :mod:`~flyover.traffic.simulate` — one run through ``libsumo`` in-process;
* :mod:`~flyover.traffic.measure` — the stable window and its throughput;
* :mod:`~flyover.traffic.batch` — runs, sample selection, tables;
* :mod:`~flyover.traffic.stats` — Welch t-tests and Table III;
* :mod:`~flyover.traffic.figures` — Fig. 4–6.

Importing this package is light: SUMO and matplotlib load where they are used.
"""

__all__: list[str] = []
