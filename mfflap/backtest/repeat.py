"""How far CFD repeats itself: one motion run several times, each a hair apart.

Two OpenFOAM runs of one optimised motion whose controlDicts differed only in the 13th digit
of endTime and writeInterval took different time steps and parted in the flow's vortex
shedding: the last cycle's mean thrust 2.8 % apart (README, "First-order corrections";
``tests/test_cfd_repeatability.py``). That spread is the noise under every back-test's
comparison and every trust-region step the rounds judge (``mfflap run
--cfd-repeatability``).

:func:`repeat_runs` measures it: copy k of a motion runs with the Courant limit multiplied
by 1 + k :data:`REPEAT_PERTURBATION` (copy 0: the settings as given), everything else the
same, and :func:`repeatability_of` compares the copies' last-cycle means. Every time step of
copy k is then that much longer: a change far below anything the flow could resolve, so
whatever the copies differ by beyond it is the flow's own sensitivity. (pimpleFoam run twice
on the same case repeats itself bit for bit, and a first time step perturbed alone is not a
probe: the solver resets it from the Courant number at the start, which cancels it; both
were found running this module, ``tests/test_cfd_repeatability.py``.)
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mfflap.errors import ConfigError

#: the relative change of the Courant limit (so of every time step) between two copies
REPEAT_PERTURBATION = 1e-6


@dataclass(frozen=True)
class Repeatability:
    """The last-cycle CFD means of several runs of one motion.

    Attributes
    ----------
    label, key : the motion's label and key
    mean_thrust : N, one per run
    mean_power : W, one per run
    sources : where each run comes from (a record's name and how it was had)
    ran_otherwise : how a run did not run as the first did (a retry's far field or Courant
        limit, :func:`~mfflap.backtest.as_run.as_run_differences`), or mixed two set-ups in
        the cycles compared (a retry resumed it within them); empty: the runs ran alike, and
        their spread is CFD's repeatability
    """

    label: str
    key: str
    mean_thrust: np.ndarray
    mean_power: np.ndarray
    sources: tuple[str, ...]
    ran_otherwise: tuple[str, ...] = ()

    @staticmethod
    def _spread(values: np.ndarray) -> float:
        centre = abs(float(np.mean(values)))
        return float(np.ptp(values)) / centre if centre > 0 else float("inf")

    @property
    def thrust_spread(self) -> float:
        """(largest - smallest) / |mean| of the runs' mean thrust."""
        return self._spread(self.mean_thrust)

    @property
    def power_spread(self) -> float:
        """(largest - smallest) / |mean| of the runs' mean power."""
        return self._spread(self.mean_power)

    @property
    def alike(self) -> bool:
        """Whether the runs ran alike, so that their spread is CFD's repeatability."""
        return not self.ran_otherwise

    @property
    def share(self) -> float:
        """The larger spread: what ``mfflap run --cfd-repeatability`` takes."""
        return max(self.thrust_spread, self.power_spread)

    def describe(self) -> str:
        """One line: the runs' means and their spreads."""
        return (f"{self.label}: {len(self.sources)} runs, mean thrust "
                + ", ".join(f"{t:.4g}" for t in self.mean_thrust)
                + f" N (spread {self.thrust_spread:.2%}), mean power "
                + ", ".join(f"{p:.4g}" for p in self.mean_power)
                + f" W (spread {self.power_spread:.2%})"
                + ("" if self.alike else "; not a repeatability: the runs did not run alike ("
                   + "; ".join(self.ran_otherwise) + "), and their spread holds that too"))

    def as_dict(self) -> dict:
        """JSON-friendly."""
        return {"label": self.label, "motion_key": self.key,
                "mean_thrust": [float(t) for t in self.mean_thrust],
                "mean_power": [float(p) for p in self.mean_power],
                "thrust_spread": self.thrust_spread, "power_spread": self.power_spread,
                "share": self.share, "sources": list(self.sources),
                "alike": self.alike, "ran_otherwise": list(self.ran_otherwise)}


def repeatability_of(records: Sequence, label: str, model, period: float,
                     max_power: float, *, average_cycles: int = 1) -> Repeatability:
    """Compare the last cycles of ``records`` (:class:`~mfflap.campaign.records.CfdRecord`
    of one motion) as the back-test does (:func:`~mfflap.backtest.compare.compare_last_cycle`),
    or the means over their last ``average_cycles`` cycles. Runs that a retry left with
    another far field or Courant limit than the first, or whose compared cycles it split
    between two set-ups, are named in ``ran_otherwise``: their spread is no repeatability.

    Raises
    ------
    ConfigError
        Fewer than two records, or records of different motions (key ``repeat``).
    """
    from mfflap.backtest.as_run import as_run_differences
    from mfflap.backtest.compare import compare_last_cycle

    if len(records) < 2:
        raise ConfigError(f"a repeatability needs two runs or more, got {len(records)}",
                          key="repeat")
    keys = {r.parameters.get("motion_key") for r in records}
    if len(keys) != 1:
        raise ConfigError(f"the runs compared are of different motions: {sorted(map(str, keys))}",
                          key="repeat")
    means = [compare_last_cycle(r, model, period, max_power, average_cycles=average_cycles)
             for r in records]
    otherwise = [f"{r.name}: {d}" for r in records[1:]
                 for d in as_run_differences(records[0], r)]
    otherwise += [f"{r.name}: compared cycles mix two set-ups (its settings changed at t = "
                  f"{m.cfd_settings_since_s:.4g} s)"
                  for r, m in zip(records, means, strict=True) if m.compared_cycles_mixed_set_up]
    return Repeatability(label, str(keys.pop()),
                         np.array([m.cfd_mean_thrust for m in means]),
                         np.array([m.cfd_mean_power for m in means]),
                         tuple(r.name for r in records), tuple(otherwise))


def copy_settings(solver, copy: int):
    """The solver settings of copy ``copy`` (module docstring; copy 0: ``solver`` itself)."""
    from mfflap.cfd.openfoam.writer import SolverSettings

    base = solver or SolverSettings()
    return replace(base, max_courant=base.max_courant * (1 + copy * REPEAT_PERTURBATION))


def repeat_runs(motion, label: str, model, max_power: float, *, copies: int,
                work_dir: str | Path, save_to: str | Path | None = None, n_cycles: float = 3.0,
                mesh: str = "coarse", solver=None, plate=None, fluid=None, stream=None,
                progress: Callable[[str], None] | None = None,
                average_cycles: int = 1, retries_from_start: bool = False,
                n_procs: int = 1) -> Repeatability:
    """Run ``motion`` ``copies`` times in OpenFOAM (module docstring) and compare them: their
    last cycles, or their means over the last ``average_cycles`` cycles.

    ``mesh``, ``solver``, ``plate``, ``fluid``, ``stream``, ``retries_from_start`` and
    ``n_procs`` as for a live back-test (:func:`~mfflap.backtest.run.backtest_motion`; a
    saved copy retried part-way is then run again). Each copy is a case
    ``work_dir/backtest_<key>_copy<k>`` (with ``_<n>cycles`` after it for other than 3
    periods; a killed run resumes there) and, with ``save_to``, a record
    ``backtest_<key>_copy<k>.h5`` there, which a later call for as many periods takes
    instead of running the copy again.

    Raises
    ------
    ConfigError
        ``copies`` below 2.
    MfflapError
        A copy's run failed (the copies before it are kept).
    """
    from mfflap.backtest.as_run import as_run_since_s
    from mfflap.backtest.run import cfd_motion, motion_key, run_backtest_case
    from mfflap.campaign.records import read_record, write_record

    if not (isinstance(copies, int) and copies >= 2):
        raise ConfigError(f"--repeat must be 2 or more runs, got {copies!r}", key="repeat")
    key = motion_key(motion)
    period = cfd_motion(motion).period
    records = []
    for k in range(copies):
        name = f"backtest_{key}_copy{k}"
        saved = None if save_to is None else Path(save_to) / f"{name}.h5"
        limit = copy_settings(solver, k).max_courant
        if saved is not None and saved.is_file():
            record = read_record(saved)
            had = float(record.provenance.get("solver_max_courant", float("nan")))
            cycles = float(record.parameters.get("n_cycles", 3.0))
            part_way = retries_from_start and as_run_since_s(record) > 0.0
            if (np.isclose(had, limit, rtol=1e-12, atol=0) and np.isclose(cycles, n_cycles)
                    and not part_way):
                if progress is not None:
                    progress(f"copy {k} of {copies}: taken from {saved}")
                records.append(record)
                continue
        if progress is not None:
            progress(f"copy {k} of {copies}: Courant limit {limit!r}")
        record = run_backtest_case(motion, label, name, work_dir=work_dir, n_cycles=n_cycles,
                                   mesh=mesh, solver=copy_settings(solver, k), plate=plate,
                                   fluid=fluid, stream=stream, progress=progress,
                                   parameters={"copy": k},
                                   retries_from_start=retries_from_start, n_procs=n_procs)
        if saved is not None:
            write_record(saved, record, single_precision=True)
        records.append(record)
    return repeatability_of(records, label, model, period, max_power,
                            average_cycles=average_cycles)


__all__ = ["REPEAT_PERTURBATION", "Repeatability", "copy_settings", "repeat_runs",
           "repeatability_of"]
