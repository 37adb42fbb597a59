"""Batch scoring of shape collections, on one machine or a Dask cluster.

* ``inputs``  which shapes: files, folders, glob patterns; content hashes
* ``schema``  the table's columns, their types and meanings
* ``rows``    one shape -> one row (the task a worker runs)
* ``table``   Parquet / CSV / JSON Lines output, appended loss-free by one writer
* ``run``     ``run_batch``: plan, resume, run, summarise
"""

from .run import BatchSummary, format_summary, run_batch
from .schema import COLUMNS

__all__ = ["BatchSummary", "COLUMNS", "format_summary", "run_batch"]
