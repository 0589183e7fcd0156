"""The CFD means of a back-test cycle by cycle: how far one cycle's mean stands for the run's.

A back-test compares the model with CFD's mean thrust and power over the last simulated
cycle. Past its start-up, a flapping plate meets the vortices it shed before, and at large
heave amplitudes that meeting is not the same from one cycle to the next: a ten-cycle coarse
mesh run of the trust series' beta = 0 optimum (docs/findings/optimised_motions.md, "How long a
back-test runs") has cycle means of 24.7-32.6 N after its third cycle, a scatter of 9 % of
their mean, where two copies of its three-cycle run agree within 0.7 %
(:mod:`mfflap.backtest.repeat`: the copies part only after their third cycle). One cycle's
mean is then one draw of that scatter, and the mean over several cycles is what the motion
makes: two ten-period copies' eight-cycle means agree within 0.05 %. The standard error
assumes independent cycles, and it covers only the run's own settings: a run whose time step
collapsed and was retried at half the Courant limit
(:func:`~mfflap.cfd.openfoam.run_motion.run_motion`; the record's ``retries``) settles
elsewhere (7 % at the beta = 0.5 optimum).

:func:`cycle_means` takes each whole cycle of a record, counted back from its end as
:func:`~mfflap.backtest.compare.compare_last_cycle` counts its last cycle, after the start-up
ramp, with the CFD's numerical bursts bridged first (:mod:`mfflap.records.bursts`).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from mfflap.errors import ConfigError
from mfflap.metrics import time_mean
from mfflap.performance import thrust_and_power
from mfflap.records.bursts import bridge_load_bursts
from mfflap.records.record import CfdRecord

#: fraction of a period a cycle may start before the earliest start asked for
_START_SLACK = 1e-4


@dataclass(frozen=True)
class CycleMeans:
    """Mean CFD thrust and input power over each whole cycle of a run, oldest first.

    Attributes
    ----------
    record : the run's name
    period_s : s
    start_s : s, where each cycle starts
    thrust : N, one mean per cycle
    power : W, one mean per cycle
    """

    record: str
    period_s: float
    start_s: np.ndarray
    thrust: np.ndarray
    power: np.ndarray

    @property
    def n_cycles(self) -> int:
        """The cycles held."""
        return len(self.thrust)

    @property
    def numbers(self) -> np.ndarray:
        """Each cycle's number counted from the run's start: the period it starts in (1: the
        one with the ramp; a cycle from 0.5 P to 1.5 P is cycle 1)."""
        return np.floor(self.start_s / self.period_s + _START_SLACK).astype(int) + 1

    def after(self, n_skipped: int) -> CycleMeans:
        """The cycles held but the first ``n_skipped`` (start-up).

        Raises
        ------
        ConfigError
            None would be left, or ``n_skipped`` below 0 (key ``skip_cycles``).
        """
        if not (isinstance(n_skipped, int | np.integer) and 0 <= n_skipped < self.n_cycles):
            raise ConfigError(f"{self.record}: {n_skipped!r} start-up cycle(s) left out of its "
                              f"{self.n_cycles} whole cycle(s) after the ramp leave none",
                              key="skip_cycles")
        return self.last(self.n_cycles - n_skipped)

    def last(self, n_cycles: int) -> CycleMeans:
        """The last ``n_cycles`` cycles.

        Raises
        ------
        ConfigError
            Fewer cycles held than asked for, or fewer than one asked for (key
            ``average_cycles``, naming the record).
        """
        if not (isinstance(n_cycles, int | np.integer) and 1 <= n_cycles <= self.n_cycles):
            raise ConfigError(
                f"{self.record}: the mean of its last {n_cycles!r} cycle(s) was asked for, but "
                f"it holds {self.n_cycles} whole cycle(s) of {self.period_s:.6g} s after its "
                "start-up ramp; run it for more cycles (mfflap backtest --live --cycles)",
                key="average_cycles")
        return CycleMeans(self.record, self.period_s, self.start_s[-n_cycles:],
                          self.thrust[-n_cycles:], self.power[-n_cycles:])

    @property
    def mean_thrust(self) -> float:
        """N, the mean over the cycles held."""
        return float(np.mean(self.thrust))

    @property
    def mean_power(self) -> float:
        """W, the mean over the cycles held."""
        return float(np.mean(self.power))

    @staticmethod
    def _error(values: np.ndarray) -> float:
        return (float(np.std(values, ddof=1) / np.sqrt(len(values))) if len(values) > 1
                else float("nan"))

    @property
    def thrust_standard_error(self) -> float:
        """N, the sample standard deviation of the cycle means over the root of their number
        (NaN with one cycle). Consecutive cycles are taken as independent draws."""
        return self._error(self.thrust)

    @property
    def power_standard_error(self) -> float:
        """W, as :attr:`thrust_standard_error`."""
        return self._error(self.power)

    @staticmethod
    def _scatter(values: np.ndarray) -> float:
        if len(values) < 2:
            return float("nan")
        centre = abs(float(np.mean(values)))
        return float(np.std(values, ddof=1)) / centre if centre > 0 else float("inf")

    @property
    def thrust_scatter(self) -> float:
        """One cycle's mean thrust's standard deviation over |the mean|: the noise of a
        back-test that reads one cycle (NaN with one cycle)."""
        return self._scatter(self.thrust)

    @property
    def power_scatter(self) -> float:
        """As :attr:`thrust_scatter`, of the power."""
        return self._scatter(self.power)

    def describe(self) -> str:
        """One line: the cycle means and their mean with its standard error."""
        if self.n_cycles < 2:
            return (f"{self.record}: 1 cycle, mean thrust {self.mean_thrust:.4g} N, mean power "
                    f"{self.mean_power:.4g} W (no cycle-to-cycle scatter from one cycle)")
        return (f"{self.record}: {self.n_cycles} cycles, mean thrust "
                f"{self.mean_thrust:.4g} ± {self.thrust_standard_error:.2g} N (cycles "
                + ", ".join(f"{t:.4g}" for t in self.thrust)
                + f"; one cycle's scatter {self.thrust_scatter:.1%}), mean power "
                f"{self.mean_power:.4g} ± {self.power_standard_error:.2g} W (one cycle's "
                f"scatter {self.power_scatter:.1%})")

    def as_dict(self) -> dict:
        """JSON-friendly (NaN as None)."""
        def num(x: float) -> float | None:
            return None if np.isnan(x) else float(x)
        return {"record": self.record, "period_s": self.period_s,
                "cycle_start_s": [float(s) for s in self.start_s],
                "cycle_mean_thrust": [float(t) for t in self.thrust],
                "cycle_mean_power": [float(p) for p in self.power],
                "mean_thrust": self.mean_thrust, "mean_power": self.mean_power,
                "thrust_standard_error": num(self.thrust_standard_error),
                "power_standard_error": num(self.power_standard_error),
                "thrust_scatter": num(self.thrust_scatter),
                "power_scatter": num(self.power_scatter)}


def record_period(record: CfdRecord) -> float:
    """A record's period, s: its ``period`` parameter (a back-test), else 1 / ``frequency``
    (a sinusoid).

    Raises
    ------
    ConfigError
        A record of a motion meant not to repeat (the identification's pitch ramp,
        ``ramp_harmonic``), or with neither parameter (key ``period``, naming the record).
    """
    params = record.parameters
    if params.get("kind") == "ramp_harmonic":
        raise ConfigError(f"{record.name}: a sinusoid with the pitch ramp theta_kamp t, whose "
                          "cycles are not meant to repeat; its cycle means say nothing of "
                          "periodicity", key="period")
    if "period" in params:
        return float(params["period"])
    if float(params.get("frequency", 0.0)) > 0:
        return 1.0 / float(params["frequency"])
    raise ConfigError(f"{record.name}: its parameters give no period or frequency "
                      f"({sorted(params)})", key="period")


def cycles_figure(runs: list[tuple[CycleMeans, CycleMeans]],
                  labels: list[str] | None = None):
    """Mean thrust and power per cycle of each run, with the mean over its settled cycles
    and its standard error as a band; ``runs``: (every cycle, the settled ones) per run,
    each in a colour of its own (up to 20), named by ``labels`` (default: the records'
    names) in a legend beside the axes."""
    # matplotlib takes about a second to load: only figures need it
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    labels = labels or [every.record for every, _ in runs]
    colours = plt.get_cmap("tab20" if len(runs) > 10 else "tab10").colors
    fig, axes = plt.subplots(1, 2, figsize=(14, 4.2))
    for k, ((every, settled), label) in enumerate(zip(runs, labels, strict=True)):
        for ax, values, mean, error in (
                (axes[0], every.thrust, settled.mean_thrust, settled.thrust_standard_error),
                (axes[1], every.power, settled.mean_power, settled.power_standard_error)):
            line = ax.plot(every.numbers, values, "o-", ms=4, lw=1, label=label,
                           color=colours[k % len(colours)])[0]
            span = (settled.numbers[0] - 0.3, settled.numbers[-1] + 0.3)
            ax.hlines(mean, *span, color=line.get_color(), lw=1, ls="--")
            if not np.isnan(error):
                ax.fill_between(span, mean - error, mean + error, color=line.get_color(),
                                alpha=0.15)
    axes[0].set_ylabel("CFD mean thrust per cycle [N]")
    axes[1].set_ylabel("CFD mean input power per cycle [W]")
    for ax in axes:
        ax.set_xlabel("cycle (1: with the start-up ramp)")
        ax.xaxis.get_major_locator().set_params(integer=True)
    axes[1].legend(fontsize=7, loc="upper left", bbox_to_anchor=(1.02, 1.0))
    fig.suptitle("dashed: mean over the settled cycles; band: its standard error", fontsize=9)
    fig.tight_layout()
    return fig


def cycle_means(record: CfdRecord, period: float, *, after_s: float | None = None
                ) -> CycleMeans:
    """Mean thrust and power of each whole cycle of ``record`` (module docstring).

    Parameters
    ----------
    period : s
    after_s : s, optional
        The earliest start of a cycle taken (default: the record's ``ramp_time`` parameter,
        else 0).

    Raises
    ------
    ConfigError
        A non-positive period, or no whole cycle after ``after_s`` (key ``period``, naming
        the record).
    """
    if not period > 0:
        raise ConfigError(f"{record.name}: the period must be > 0 s, got {period!r}",
                          key="period")
    t = record.time
    start = float(record.parameters.get("ramp_time", 0.0)) if after_s is None else after_s
    end = float(t[-1])
    # a cycle may start a ten-thousandth of a period before ``after_s``: the times a solver
    # writes are rounded (a run of 2.5 periods ends at 1.15100043 s, 2.5 P is 1.1510004334 s)
    n = int(np.floor((end - max(start, float(t[0]))) / period + _START_SLACK))
    if n < 1:
        raise ConfigError(f"{record.name}: no whole cycle of {period:.6g} s between "
                          f"{start:.6g} s and its end at {end:.6g} s", key="period")
    starts = end - period * np.arange(n, 0, -1)
    loads, _ = bridge_load_bursts(record.loads, t >= starts[0])
    thrust, power = thrust_and_power(loads, record.state)
    last = len(starts) - 1
    means_t, means_p = [], []
    for k, s in enumerate(starts):
        # each cycle [s, s + period): the last one closed, as compare_last_cycle takes it
        inside = (t >= s) & ((t < s + period) if k < last else (t <= end))
        means_t.append(time_mean(t[inside], thrust[inside]))
        means_p.append(time_mean(t[inside], power[inside]))
    return CycleMeans(record.name, float(period), starts, np.array(means_t), np.array(means_p))


__all__ = ["CycleMeans", "cycle_means", "cycles_figure", "record_period"]
