"""Analytics over the results tables with DuckDB, where they lie (no copies, no import step).

:func:`connect` opens an in-memory DuckDB with one view per results table
(:data:`~flyover.analytics.views.VIEWS`); hive-partitioned tables (``fuel``)
are read as such. :func:`query` runs SQL (or a named query,
:data:`~flyover.analytics.queries.NAMED_QUERIES`) and returns a
:class:`pyarrow.Table`.
"""

from __future__ import annotations

from flyover.analytics.views import (
    VIEWS, AnalyticsError, MissingTableError, TableSource, connect, query,
)
from flyover.analytics.queries import NAMED_QUERIES, NamedQuery

__all__ = ["VIEWS", "TableSource", "AnalyticsError", "MissingTableError", "connect", "query",
           "NAMED_QUERIES", "NamedQuery"]
