"""Back-test of optimised motions against CFD (live OpenFOAM or precomputed fixtures)."""

from mfflap.backtest.compare import BacktestComparison, compare_last_cycle
from mfflap.backtest.run import BacktestOutcome, backtest_motion, motion_key

__all__ = ["BacktestComparison", "BacktestOutcome", "backtest_motion", "compare_last_cycle",
           "motion_key"]
