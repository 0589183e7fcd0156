"""The CFD records mfflap ships: real OpenFOAM runs of the paper's Table 1 motions, of the
optimised motions' back-tests and of small motions for the check against linear theory,
one HDF5 record per run (``fixtures/<set>/<case>.h5``).

mfflap finds them through :func:`fixtures_root` (:func:`mfflap.records.record.fixture_dir`).
"""

from pathlib import Path


def fixtures_root() -> Path:
    """The folder of the record sets."""
    return Path(__file__).resolve().parent / "fixtures"
