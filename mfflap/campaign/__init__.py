"""CFD campaigns: a grid of cases, run resumably on dask, one HDF5 record per finished case."""

from mfflap.campaign.cases import CfdCase, grid_cases
from mfflap.records.record import CfdRecord, read_record, read_records, write_record

__all__ = ["CfdCase", "CfdRecord", "grid_cases", "read_record", "read_records", "write_record"]
