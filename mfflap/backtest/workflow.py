"""Back-test every optimised motion of an optimisation study, and the best sinusoid."""

from __future__ import annotations

from collections.abc import Callable, Sequence
from pathlib import Path

from mfflap.backtest.run import BacktestOutcome, backtest_motion
from mfflap.cfd.openfoam.case_path import check_case_path
from mfflap.cfd.openfoam.writer import SolverSettings
from mfflap.config import CaseConfig
from mfflap.kinematics.discrete import DiscreteMotion
from mfflap.performance import no_thrust_gain_reason, thrust_gain


def backtest_all(config: CaseConfig, motions: dict[str, DiscreteMotion], model, *,
                 fixture_folders: Sequence[str | Path], live: bool = False,
                 work_dir: str | Path | None = None, save_to: str | Path | None = None,
                 mesh: str = "coarse", solver: SolverSettings | None = None,
                 progress: Callable[[str], None] | None = None,
                 into: dict[str, BacktestOutcome] | None = None,
                 done_folders: Sequence[str | Path] = (), n_cycles: float = 3.0,
                 average_cycles: int = 1, retries_from_start: bool = False,
                 n_procs: int = 1) -> dict[str, BacktestOutcome]:
    """Back-test each labelled motion (a failure of one does not stop the others).

    ``into``, if given, receives each outcome as soon as it is known and is returned, so
    that a caller stopped part-way (Ctrl-C during a live run) keeps the back-tests done
    before. ``done_folders``: live, records of a motion run before on this set-up, taken
    instead of a new run (:func:`~mfflap.backtest.run.backtest_motion`, which also says
    what ``n_cycles``, the periods of a live run, ``average_cycles``, the cycles the
    means are taken over, ``retries_from_start``, a live run's retries from t = 0 s, and
    ``n_procs``, the processes a live run is decomposed on, do).

    Raises
    ------
    ConfigError
        Live, before any run, if ``work_dir``'s path holds characters OpenFOAM strips
        (:func:`~mfflap.cfd.openfoam.case_path.check_case_path`).
    """
    out = {} if into is None else into
    if live and work_dir is not None:
        check_case_path(work_dir)  # before any run, not once per motion
    for label, motion in motions.items():
        if progress is not None:
            progress(f"back-test {label}: {'running OpenFOAM' if live else 'looking up CFD'}")
        out[label] = backtest_motion(
            motion, label, model, config.optimisation.max_power,
            fixture_folders=fixture_folders, live=live, work_dir=work_dir, mesh=mesh,
            plate=config.plate, fluid=config.fluid, stream=config.flow, save_to=save_to,
            solver=solver, done_folders=done_folders, n_cycles=n_cycles,
            average_cycles=average_cycles, retries_from_start=retries_from_start,
            n_procs=n_procs, progress=None if progress is None else (
                lambda message, label=label: progress(f"back-test {label}: {message}")))
        if progress is not None:
            o = out[label]
            progress(f"back-test {label}: {o.status} ({o.source})")
    return out


def gain_in_cfd(outcomes: dict[str, BacktestOutcome], optimised: str = "β = 0",
                baseline: str = "best sinusoid") -> float | None:
    """CFD mean thrust of the optimised motion over the best sinusoid's, minus one.

    None when either was not back-tested, or the best sinusoid makes no thrust in CFD
    (:func:`no_gain_in_cfd_reason` says which).
    """
    a, b = outcomes.get(optimised), outcomes.get(baseline)
    if a is None or b is None or a.comparison is None or b.comparison is None:
        return None
    return thrust_gain(a.comparison.cfd_mean_thrust, b.comparison.cfd_mean_thrust)


def no_gain_in_cfd_reason(outcomes: dict[str, BacktestOutcome], optimised: str = "β = 0",
                          baseline: str = "best sinusoid") -> str | None:
    """Why :func:`gain_in_cfd` is None; None when it is a number."""
    for label in (optimised, baseline):
        if label not in outcomes:
            return f"there is no {label} motion (not optimised)"
        if outcomes[label].comparison is None:
            return f"{label} was not back-tested"
    if gain_in_cfd(outcomes, optimised, baseline) is None:
        return no_thrust_gain_reason(outcomes[baseline].comparison.cfd_mean_thrust,
                                     f"the {baseline} in CFD")
    return None
