"""``mfflap backtest``: check optimised motions against CFD."""

from __future__ import annotations

from pathlib import Path

import click
import numpy as np

from mfflap.cli.json_output import echo_json
from mfflap.cli.options import (
    cfd_settings,
    mesh_and_setup_options,
    refuse_given,
    refuse_settings,
    set_option,
)


@click.command()
@click.argument("optimisation_file", type=click.Path(dir_okay=False, exists=True,
                                                     path_type=Path))
@click.option("--live", is_flag=True, help="Run OpenFOAM (else use precomputed fixtures).")
@click.option("--work", "work_dir", type=click.Path(file_okay=False, path_type=Path),
              default=Path("backtest_cases"), show_default=True, help="OpenFOAM case folder.")
@click.option("--fixtures", "fixture_folders", multiple=True,
              type=click.Path(file_okay=False, exists=True, path_type=Path),
              help="Folders of back-test records (default: the shipped ones).")
@click.option("--save-to", type=click.Path(file_okay=False, path_type=Path), default=None,
              help="Write live runs as back-test records (fixtures) here; a motion whose "
                   "record is there already, run for this case on the same mesh and "
                   "set-up, is not run again.")
@click.option("--motion", "only", multiple=True,
              help="Back-test only this motion: 'best sinusoid' or a beta ('0', '0.5' or "
                   "'β = 0'); repeat for several (default: every motion).")
@mesh_and_setup_options(" of live runs")
@click.option("--repeat", "repeat", type=int, default=None,
              help="With --live: run each motion this many times (2 or more), each copy's "
                   "Courant limit a millionth apart, and print how far their mean thrust "
                   "and power spread: CFD's repeatability, which mfflap run "
                   "[rounds] cfd_repeatability takes.")
@set_option()
@click.option("--json", "as_json", is_flag=True)
def backtest(optimisation_file: Path, live: bool, work_dir: Path,
             fixture_folders: tuple[Path, ...], save_to: Path | None, only: tuple[str, ...],
             mesh: str | None, setup_name: str | None, repeat: int | None,
             settings: tuple[str, ...], as_json: bool) -> None:
    """Back-test the optimised motions (and the best sinusoid) of OPTIMISATION_FILE.

    The periods a live run simulates and the cycles its means are taken over are the
    [backtest] table of the case stored in the file, and how a live run is set up, retried
    and spread over ranks its [cfd] table; --set backtest.KEY=VALUE or cfd.KEY=VALUE
    changes them for this back-test. Ctrl-C stops the run in flight and shows the motions
    back-tested before it. The exit status is 1 when a motion could not be back-tested
    (each is listed with why).
    """
    from mfflap.backtest.workflow import backtest_all
    from mfflap.cfd.openfoam.setups import case_mesh_and_solver
    from mfflap.config import stored_case
    from mfflap.optimisation.store import beta_label, read_result, read_sweep
    from mfflap.optimisation.study import sinusoid_motion
    from mfflap.records.record import backtest_fixture_dirs
    from mfflap.results import ResultsFile

    if not live:  # the fixtures' runs are read as they were made
        why = ("live runs (--live); without it the back-test reads CFD records "
               "(--fixtures), run on the mesh and set-up they were made with")
        refuse_given(("work_dir", "save_to", "mesh", "setup_name", "repeat"), why)
        refuse_settings(settings, "cfd", why)
        refuse_settings(settings, "backtest.cycles", why)
    with ResultsFile(optimisation_file, kinds=("optimisation", "run")) as rf:
        case = stored_case(rf.config_toml, source=f"{optimisation_file}:/inputs",
                          settings=cfd_settings(settings, mesh, setup_name))
        # a file of optima alone (OptimisedMotion.to_hdf5) has no sweep and so no best
        # sinusoid to back-test beside them
        sweep_best = (read_sweep(rf, "optimisation/sweep") if "optimisation/sweep" in rf.h5
                      else None)
        model = optimised_with(rf, case)
        motions, scales = {}, {}
        for key in sorted(rf.h5["optimisation/sqp"]):
            r = read_result(rf, f"optimisation/sqp/{key}")
            motions[beta_label(r.beta)] = r.motion
            attrs = rf.h5[f"optimisation/sqp/{key}"].attrs
            if "setting_output_thrust_scale" in attrs:  # optimised with corrected outputs
                scales[beta_label(r.beta)] = (float(attrs["setting_output_thrust_scale"]),
                                             float(attrs["setting_output_power_scale"]))
    spec, solver = case_mesh_and_solver(case.cfd, case.source)
    n_cycles, average_cycles = case.backtest.simulated_periods, case.backtest.average_cycles
    retries_from_start, n_procs = case.cfd.retries_from_start, case.cfd.procs
    n = next(iter(motions.values())).n_steps
    if sweep_best is not None:
        motions = {"best sinusoid": sinusoid_motion(*sweep_best, n), **motions}
    motions = _chosen(motions, only)
    click.echo("model: the coefficients the motions were optimised with, " + ", ".join(
        f"{k} {v:.3g}" for k, v in model.coefficients.items()), err=True)
    if repeat is not None:
        _repeat(case, motions, model, repeat, work_dir, save_to, spec.name, solver, as_json,
                n_cycles, average_cycles, retries_from_start, n_procs)
        return
    folders = list(fixture_folders) or backtest_fixture_dirs()
    outcomes: dict = {}
    interrupted = None
    try:
        backtest_all(case, motions, model, fixture_folders=folders,
                     live=live, work_dir=work_dir, save_to=save_to, mesh=spec.name,
                     solver=solver, progress=lambda m: click.echo(m, err=True), into=outcomes,
                     done_folders=() if save_to is None else (save_to,), n_cycles=n_cycles,
                     average_cycles=average_cycles, retries_from_start=retries_from_start,
                     n_procs=n_procs)
    except KeyboardInterrupt:  # the solver is stopped by then; show what was back-tested
        interrupted = next((label for label in motions if label not in outcomes), "the last")
    from mfflap.performance import discrete_means

    _show(outcomes, as_json, scales, {
        label: discrete_means(model, motions[label], case.optimisation.scheme)
        for label in scales if label in motions})
    if interrupted is not None:
        click.echo(f"interrupted during the back-test of {interrupted}: {len(outcomes)} of "
                   f"{len(motions)} motions back-tested{' (shown above)' if outcomes else ''};"
                   " the same command "
                   + (f"resumes the live runs in {work_dir} from their last written times"
                      if live else "back-tests them all again"), err=True)
        raise click.Abort()
    missing = [label for label, o in outcomes.items() if o.status != "back-tested"]
    if missing:  # listed above with why; a script must not take the back-test as complete
        click.echo(f"exit status 1: {len(missing)} of {len(outcomes)} motions not "
                   f"back-tested ({', '.join(missing)})", err=True)
        raise SystemExit(1)


def check_cycles(cycles: float | None, average_cycles: int, option: str = "--cycles") -> float:
    """The periods of a live run (``option``, default 3), checked with ``--average-cycles``
    against the whole cycles it holds after its start-up ramp of half a period.

    Raises
    ------
    click.BadParameter
        Fewer than one whole cycle after the ramp, fewer than one cycle averaged, or more
        averaged than a live run of ``cycles`` periods holds.
    """
    n_cycles = 3.0 if cycles is None else float(cycles)
    if not (np.isfinite(n_cycles) and n_cycles >= 1.5):
        raise click.BadParameter(f"must be 1.5 or more periods (a whole cycle after the "
                                 f"start-up ramp of half a period), got {cycles}",
                                 param_hint=option)
    if average_cycles < 1:
        raise click.BadParameter(f"must be 1 or more cycles, got {average_cycles}",
                                 param_hint="--average-cycles")
    held = int(np.floor(n_cycles - 0.5 + 1e-9))
    if cycles is not None and average_cycles > held:
        raise click.BadParameter(f"{average_cycles} cycles averaged, but a run of {option} "
                                 f"{n_cycles:g} holds {held} whole cycle(s) after its "
                                 "start-up ramp of half a period",
                                 param_hint="--average-cycles")
    return n_cycles


def _repeat(case, motions: dict, model, copies: int, work_dir: Path, save_to: Path | None,
            mesh: str, solver, as_json: bool, n_cycles: float = 3.0,
            average_cycles: int = 1, retries_from_start: bool = False,
            n_procs: int = 1) -> None:
    """``--repeat``: each motion's copies (:func:`mfflap.backtest.repeat.repeat_runs`)."""
    from mfflap.backtest.repeat import repeat_runs
    from mfflap.cfd.openfoam.case_path import check_case_path

    if copies < 2:
        raise click.BadParameter(f"must be 2 or more runs, got {copies}",
                                 param_hint="--repeat")
    check_case_path(work_dir)
    found = {}
    for label, motion in motions.items():
        found[label] = repeat_runs(
            motion, label, model, case.optimisation.max_power, copies=copies,
            work_dir=work_dir, save_to=save_to, mesh=mesh, solver=solver, plate=case.plate,
            fluid=case.fluid, stream=case.flow, n_cycles=n_cycles,
            average_cycles=average_cycles, retries_from_start=retries_from_start,
            n_procs=n_procs,
            progress=lambda m, label=label: click.echo(f"repeat {label}: {m}", err=True))
    if as_json:
        echo_json({"repeatability": {label: r.as_dict() for label, r in found.items()}})
        return
    for r in found.values():
        click.echo(r.describe())
    alike = [r for r in found.values() if r.alike]
    if not alike:  # a spread of runs made otherwise is no measure of CFD's noise
        click.echo("CFD's repeatability: not measured: no motion's runs ran alike (a retry "
                   "changed the far field or the Courant limit of some; "
                   "docs/findings/optimised_motions.md, 'Retries and one set-up')")
        return
    worst = max(alike, key=lambda r: r.share)
    click.echo(f"CFD's repeatability: {worst.share:.2%} ({worst.label}"
               + (f"; of the {len(alike)} motions whose runs ran alike"
                  if len(alike) < len(found) else "")
               + f"); mfflap run --set rounds.cfd_repeatability={worst.share:.3g}")


def _chosen(motions: dict, only: tuple[str, ...]) -> dict:
    """The motions ``--motion`` names (all without it), in the file's order.

    Raises
    ------
    click.BadParameter
        Naming a motion the file does not hold, and those it does.
    """
    from mfflap.optimisation.store import beta_label

    if not only:
        return motions
    wanted = set()
    for name in only:
        label = name.strip()
        if label not in motions:  # a beta: "0.5", "beta 0.5", "β=0.5"
            token = label.removeprefix("beta").removeprefix("β").strip(" =")
            try:
                label = beta_label(float(token))
            except ValueError:
                pass
        if label not in motions:
            raise click.BadParameter(f"{name!r} is none of the file's motions: "
                                     f"{', '.join(map(repr, motions))}", param_hint="--motion")
        wanted.add(label)
    return {k: m for k, m in motions.items() if k in wanted}


def optimised_with(rf, case):
    """The model the motions of an optimisation or run file were optimised with: the case's
    with the coefficients stored beside them (runs with identified coefficients), or
    the case's own for files written before they were stored."""
    import json

    stored = rf.h5["optimisation"].attrs.get("model_coefficients")
    model = case.morison_model()
    return model if stored is None else model.with_coefficients(json.loads(stored))


def _error(data: dict, signal: str) -> str:
    """' ± <standard error>' of a back-test's CFD mean over several cycles, else ''."""
    error = data.get(f"cfd_{signal}_standard_error")
    return "" if error is None else f" ± {error:.2g}"


def _show(outcomes: dict, as_json: bool, scales: dict | None = None,
          optimised: dict | None = None) -> None:
    """Print the back-tests: a line per motion, or JSON. ``scales``: label -> (thrust, power)
    scale of the output correction a motion was optimised with; its corrected prediction,
    the scales times ``optimised`` (label -> the optimiser's own mean thrust and power, the
    means the scales were measured with; else the back-test's model means), is shown beside
    the model's own."""
    from mfflap.backtest.workflow import gain_in_cfd, no_gain_in_cfd_reason
    from mfflap.records.as_run import describe_as_run

    data = {label: {"status": o.status, "source": o.source, "motion_key": o.key,
                    **({"cfd_as_run": describe_as_run(o.record)} if o.record else {}),
                    **(o.comparison.as_dict() if o.comparison else {})}
            for label, o in outcomes.items()}
    for label, (k_t, k_p) in (scales or {}).items():
        d = data.get(label)
        if d is not None and "model_mean_thrust" in d:
            own_t, own_p = (optimised or {}).get(label, (d["model_mean_thrust"],
                                                         d["model_mean_power"]))
            d["corrected_prediction"] = {
                "thrust_scale": k_t, "power_scale": k_p, "mean_thrust": k_t * own_t,
                "mean_power": k_p * own_p, "optimised_mean_thrust": own_t,
                "optimised_mean_power": own_p}
    gain = gain_in_cfd(outcomes)
    if as_json:
        echo_json({"motions": data, "cfd_thrust_gain": gain,
                   "cfd_thrust_gain_missing": no_gain_in_cfd_reason(outcomes)})
        return
    for label, d in data.items():
        if d["status"] != "back-tested":
            click.echo(f"{label:14s} NOT BACK-TESTED: {d['source']}")
            continue
        click.echo(f"{label:14s} thrust CFD {d['cfd_mean_thrust']:.3f}{_error(d, 'thrust')} N "
                   f"model {d['model_mean_thrust']:.3f} N; power CFD "
                   f"{d['cfd_mean_power']:.3f}{_error(d, 'power')} W "
                   f"model {d['model_mean_power']:.3f} W; NRMSE thrust "
                   f"{100 * d['nrmse']['thrust']:.1f} %; CFD max power "
                   f"{d['cfd_max_power']:.1f} W"
                   + (f"; means over the last {d['cycles_averaged']} cycles"
                      if d["cycles_averaged"] > 1 else ""))
        if "corrected_prediction" in d:
            c = d["corrected_prediction"]
            click.echo(f"{'':14s} optimised with corrected outputs (thrust x "
                       f"{c['thrust_scale']:.3f}, power x {c['power_scale']:.3f}): predicted "
                       f"{c['mean_thrust']:.3f} N, {c['mean_power']:.3f} W")
        if "instead of a live run" in d["source"]:  # said here, not only in the progress
            click.echo(f"{'':14s} CFD: {d['source']}")
        if d["compared_cycles_mixed_set_up"]:
            click.echo(f"{'':14s} WARNING: "
                       + outcomes[label].comparison.describe_mixed_set_up())
    scattered = [(d["cycle_scatter"], label) for label, d in data.items()
                 if d.get("cycle_scatter") is not None and d["cycles_averaged"] >= 3]
    if scattered:
        share, label = max(scattered)
        click.echo(f"one cycle's CFD means scatter by up to {share:.1%} of the mean ({label}): "
                   "the noise of a back-test that reads one cycle; mfflap run "
                   f"--set rounds.cfd_repeatability={share:.3g}")
    if gain is not None:
        click.echo(f"beta = 0 thrust gain over the best sinusoid in CFD: {gain:+.1%}")
    else:
        click.echo(f"beta = 0 thrust gain in CFD: not given: {no_gain_in_cfd_reason(outcomes)}")
