"""The settings the shipped back-test fixtures and series of rounds were optimised with,
for the tests that find them: coefficients identified from the ``table1_coarse`` records
where a run identifies, the case file's coefficients, the free phase, residuals over the
grid's RMS and the means of each back-test's last cycle. Later ``--set`` pairs (a
weighting, the fixed phase) override them."""

from mfflap.records.record import fixture_dir

SHIPPED_SETTINGS = ("optimisation.coefficients=case", "optimisation.phase=free",
                    "identification.residual_scaling=grid", "backtest.average_cycles=1")
#: the identification records they were optimised with
SHIPPED_IDENTIFICATION = "table1_coarse"


def as_shipped(*args: str) -> list[str]:
    """``mfflap run`` options: ``--fixtures`` of :data:`SHIPPED_IDENTIFICATION`, the
    ``--set`` pairs of :data:`SHIPPED_SETTINGS`, then ``args``."""
    out: list[str] = ["--fixtures", str(fixture_dir(SHIPPED_IDENTIFICATION))]
    for setting in SHIPPED_SETTINGS:
        out += ["--set", setting]
    return [*out, *args]
