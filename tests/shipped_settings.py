"""The settings the shipped back-test fixtures and series of rounds were optimised with,
for the tests that find them: the case file's coefficients, the free phase, residuals over
the grid's RMS and the means of each back-test's last cycle. Later ``--set`` pairs (a
weighting, the fixed phase) override them."""

SHIPPED_SETTINGS = ("optimisation.coefficients=case", "optimisation.phase=free",
                    "identification.residual_scaling=grid", "backtest.average_cycles=1")


def as_shipped(*args: str) -> list[str]:
    """``--set`` pairs of :data:`SHIPPED_SETTINGS` followed by ``args``."""
    out: list[str] = []
    for setting in SHIPPED_SETTINGS:
        out += ["--set", setting]
    return [*out, *args]
