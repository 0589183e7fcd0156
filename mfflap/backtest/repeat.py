"""How far CFD repeats itself: one motion run several times, each a hair apart.

Two OpenFOAM runs of one optimised motion whose controlDicts differed only in the 13th digit
of endTime and writeInterval took different time steps and parted in the flow's vortex
shedding: the last cycle's mean thrust 2.8 % apart (docs/findings/optimised_motions.md, "First-order
corrections"; ``tests/backtest/test_repeat.py``). That spread is the noise under every
back-test's comparison and every trust-region step the rounds judge (``mfflap run
[rounds] cfd_repeatability``).

:func:`repeat_runs` measures it: copy k of a motion runs with the Courant limit multiplied
by 1 + k :data:`REPEAT_PERTURBATION` (copy 0: the settings as given), everything else the
same, and :func:`repeatability_of` compares the copies' last-cycle means. Every time step of
copy k is then that much longer: a change far below anything the flow could resolve, so
whatever the copies differ by beyond it is the flow's own sensitivity. (pimpleFoam run twice
on the same case repeats itself bit for bit, and a first time step perturbed alone is not a
probe: the solver resets it from the Courant number at the start, which cancels it; both
were found running this module, ``tests/backtest/test_repeat.py``.)
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from mfflap.backtest.compare import compare_last_cycle
from mfflap.backtest.run import cfd_motion, matching_fixture, motion_key, run_backtest_case
from mfflap.cfd.openfoam.writer import SolverSettings
from mfflap.errors import ConfigError
from mfflap.records.as_run import as_run_differences, as_run_since_s
from mfflap.records.record import read_record, write_record

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
        limit, :func:`~mfflap.records.as_run.as_run_differences`), or mixed two set-ups in
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
        """The larger spread: what ``[rounds] cfd_repeatability`` takes."""
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
    """Compare the last cycles of ``records`` (:class:`~mfflap.records.record.CfdRecord`
    of one motion) as the back-test does (:func:`~mfflap.backtest.compare.compare_last_cycle`),
    or the means over their last ``average_cycles`` cycles. Runs that a retry left with
    another far field or Courant limit than the first, or whose compared cycles it split
    between two set-ups, are named in ``ran_otherwise``: their spread is no repeatability.

    Raises
    ------
    ConfigError
        Fewer than two records, or records of different motions (key ``repeat``).
    """
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
    instead of running the copy again. Where ``save_to`` holds none of this key's copies,
    a whole set of another key's is taken when that motion lies within the back-test
    look-up's tolerance of this one or is the same periodic motion shifted in time
    (:func:`~mfflap.backtest.run.matching_fixture`: the same optimum found with other
    round-off), and the progress says whose they are.

    Raises
    ------
    ConfigError
        ``copies`` below 2.
    MfflapError
        A copy's run failed (the copies before it are kept).
    """
    if not (isinstance(copies, int) and copies >= 2):
        raise ConfigError(f"--repeat must be 2 or more runs, got {copies!r}", key="repeat")
    key = motion_key(motion)
    period = cfd_motion(motion).period
    limits = [copy_settings(solver, k).max_courant for k in range(copies)]
    saved_key, note = key, ""
    if save_to is not None:
        saved_key, note = _saved_copies_key(motion, key, Path(save_to), limits, n_cycles,
                                            retries_from_start)
    records = []
    for k in range(copies):
        name = f"backtest_{key}_copy{k}"
        saved = None if save_to is None else Path(save_to) / f"backtest_{saved_key}_copy{k}.h5"
        record = None if saved is None else _usable_copy(saved, limits[k], n_cycles,
                                                          retries_from_start)
        if record is not None:
            if progress is not None:
                progress(f"copy {k} of {copies}: taken from {saved}{note}")
            records.append(record)
            continue
        if progress is not None:
            progress(f"copy {k} of {copies}: Courant limit {limits[k]!r}")
        record = run_backtest_case(motion, label, name, work_dir=work_dir, n_cycles=n_cycles,
                                   mesh=mesh, solver=copy_settings(solver, k), plate=plate,
                                   fluid=fluid, stream=stream, progress=progress,
                                   parameters={"copy": k},
                                   retries_from_start=retries_from_start, n_procs=n_procs)
        if saved is not None:
            write_record(Path(save_to) / f"{name}.h5", record, single_precision=True)
        records.append(record)
    return repeatability_of(records, label, model, period, max_power,
                            average_cycles=average_cycles)


def _usable_copy(path: Path, limit: float, n_cycles: float, retries_from_start: bool):
    """The saved copy at ``path`` (a :class:`~mfflap.records.record.CfdRecord`) when it
    ran at the Courant ``limit`` for ``n_cycles`` periods (and, with ``retries_from_start``,
    no retry resumed it part-way), else None."""
    if not path.is_file():
        return None
    record = read_record(path)
    had = float(record.provenance.get("solver_max_courant", float("nan")))
    cycles = float(record.parameters.get("n_cycles", 3.0))
    part_way = retries_from_start and as_run_since_s(record) > 0.0
    if np.isclose(had, limit, rtol=1e-12, atol=0) and np.isclose(cycles, n_cycles) \
            and not part_way:
        return record
    return None


def _saved_copies_key(motion, key: str, save_to: Path, limits: Sequence[float],
                      n_cycles: float, retries_from_start: bool) -> tuple[str, str]:
    """The key under which ``save_to`` holds the copies to take for ``motion`` (key ``key``),
    and a note saying whose they are ("" for its own).

    Its own copies first, any of them (the missing ones then run). Else, as the back-test's
    look-up takes another key's record (:func:`~mfflap.backtest.run.matching_fixture`), the
    copies of a motion within the look-up's tolerance of this one, or of the same periodic
    motion shifted in time: the same optimum found with other round-off. Those are taken only
    when every copy asked for is there and usable: copies run now would be of another key,
    and copies of two motions are no repeatability.
    """
    if any((save_to / f"backtest_{key}_copy{k}.h5").is_file() for k in range(len(limits))):
        return key, ""
    if not save_to.is_dir():
        return key, ""
    match = matching_fixture(key, motion, [save_to], suffix="_copy0")
    if match is None:
        return key, ""
    other = match.path.name.removeprefix("backtest_").removesuffix("_copy0.h5")
    if any(_usable_copy(save_to / f"backtest_{other}_copy{k}.h5", limit, n_cycles,
                        retries_from_start) is None for k, limit in enumerate(limits)):
        return key, ""
    whose = match.shift_note() or "a motion within the look-up's tolerance of this one"
    return other, f" (saved for {other}: {whose})"


__all__ = ["REPEAT_PERTURBATION", "Repeatability", "copy_settings", "repeat_runs",
           "repeatability_of"]
