"""The dataset browser: a static HTML report of everything the pipeline made.

:func:`build_report` turns a results folder into ``results/report/index.html`` and the
pages it links (overview, one page per class and per interchange, evaluation). The pages
open from disk with no server; their tables are the DuckDB views and named queries of
:mod:`flyover.analytics`; the interactive plan view (:mod:`flyover.report.view`) is drawn
from each interchange's ``geometry.json``.
"""

from __future__ import annotations

from flyover.report.build import REPORT_PAGES, build_report
from flyover.report.data import ReportError

__all__ = ["build_report", "REPORT_PAGES", "ReportError"]
