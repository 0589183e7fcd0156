"""Command-line options that several commands share."""

import json
import math
from collections.abc import Callable, Sequence
from pathlib import Path

import click
from click.core import ParameterSource

from mfflap.errors import shown

MESH_NAMES = ("coarse, lean, medium, medium_r20, fine, graded, medium_edge10, "
              "medium_edge9, medium_edge6, medium_edge4, openfoam_md, "
              "openfoam_md_medium, openfoam_md_fine, coarse_r20")  # meshes.toml's order


class FiniteFloat(click.ParamType):
    """A finite number above a bound and at most a ceiling (a time, a number of periods),
    refused with the option's name otherwise: ``inf`` and ``nan`` pass click's own
    FloatRange.

    Parameters
    ----------
    minimum
        The bound.
    inclusive
        Whether the bound itself is allowed.
    maximum
        The largest value allowed: beyond it the work would not fit this machine or any
        flapping motion (a billion periods, a Courant number of a billion).
    """

    name = "float"

    def __init__(self, minimum: float = 0.0, inclusive: bool = False,
                 maximum: float = math.inf) -> None:
        self.minimum, self.inclusive, self.maximum = minimum, inclusive, maximum

    def convert(self, value, param, ctx) -> float:
        try:
            number = float(value)
        except (TypeError, ValueError):
            self.fail(f"{shown(value)} is not a number", param, ctx)
        above = number >= self.minimum if self.inclusive else number > self.minimum
        if not (math.isfinite(number) and above and number <= self.maximum):
            relation = ">=" if self.inclusive else ">"
            top = f" and <= {self.maximum:g}" if math.isfinite(self.maximum) else ""
            self.fail(f"must be a finite number {relation} {self.minimum:g}{top}, got "
                      f"{shown(value)}", param, ctx)
        return number


class FloatList(click.ParamType):
    """Comma-separated finite numbers (``1,2,0.5``), at least one; with ``unique`` a number
    given twice is refused, by the option's name.

    Parameters
    ----------
    unique
        Whether each number may appear only once (a grid's values, a list of betas).
    """

    name = "list"

    def __init__(self, unique: bool = True) -> None:
        self.unique = unique

    def convert(self, value, param, ctx) -> list[float]:
        if isinstance(value, list):
            return value
        parts = [v.strip() for v in str(value).split(",")]
        try:
            numbers = [float(v) for v in parts if v]
        except ValueError:
            self.fail(f"{shown(value)}: expected comma-separated numbers", param, ctx)
        if not numbers:
            self.fail(f"{shown(value)}: no numbers", param, ctx)
        if not all(math.isfinite(n) for n in numbers):
            self.fail(f"{shown(value)}: every number must be finite", param, ctx)
        if self.unique and len(set(numbers)) != len(numbers):
            twice = sorted({n for n in numbers if numbers.count(n) > 1})
            self.fail(f"{value!r}: {', '.join(f'{n:g}' for n in twice)} given twice",
                      param, ctx)
        return numbers


class NameList(click.ParamType):
    """Comma-separated names from a fixed set (``normal_force,moment``), at least one, each
    once; refused by the option's name, with the names allowed.

    Parameters
    ----------
    choices
        The allowed names, or a function that gives them (so that building the command
        line's help does not import the module that defines them).
    """

    name = "names"

    def __init__(self, choices: Sequence[str] | Callable[[], Sequence[str]]) -> None:
        self._choices = choices

    def convert(self, value, param, ctx) -> list[str]:
        if isinstance(value, list):
            return value
        choices = tuple(self._choices() if callable(self._choices) else self._choices)
        names = [v.strip() for v in str(value).split(",") if v.strip()]
        if not names:
            self.fail(f"{value!r}: no names; choose from {', '.join(choices)}", param, ctx)
        unknown = [n for n in names if n not in choices]
        if unknown:
            self.fail(f"{', '.join(unknown)}: not one of {', '.join(choices)}", param, ctx)
        twice = sorted({n for n in names if names.count(n) > 1})
        if twice:
            self.fail(f"{value!r}: {', '.join(twice)} given twice", param, ctx)
        return names


class FigureFile(click.Path):
    """A figure file to write: its suffix says the format, one of :data:`FIGURE_SUFFIXES`,
    refused by the option's name before any work (matplotlib would refuse it after)."""

    def __init__(self) -> None:
        super().__init__(dir_okay=False, path_type=Path)

    def convert(self, value, param, ctx):
        path = super().convert(value, param, ctx)
        if Path(path).suffix.lower() not in FIGURE_SUFFIXES:
            self.fail(f"{path}: a figure is written as {', '.join(FIGURE_SUFFIXES[:-1])} or "
                      f"{FIGURE_SUFFIXES[-1]}", param, ctx)
        return path


class ResultsOutput(click.Path):
    """An HDF5 results file to write ``kind`` results into: a file that holds another kind
    of results, or is not mfflap's, is refused by the option's name before any work
    (:func:`mfflap.results.check_overwrite`); the same kind is a rerun and is written over.
    """

    def __init__(self, kind: str) -> None:
        super().__init__(dir_okay=False, path_type=Path)
        self.kind = kind

    def convert(self, value, param, ctx):
        from mfflap.errors import MfflapError
        from mfflap.results import check_overwrite

        path = super().convert(value, param, ctx)
        try:
            check_overwrite(path, self.kind)
        except MfflapError as exc:
            self.fail(str(exc), param, ctx)
        return path


#: the figure formats the commands write, by suffix
FIGURE_SUFFIXES = (".png", ".pdf", ".svg")

#: a finite number > 0: a time span, a number of periods, a time step
POSITIVE = FiniteFloat()
#: a finite number >= 0: a start-up ramp, a time discarded
NON_NEGATIVE = FiniteFloat(inclusive=True)
#: a number of periods a CFD run simulates: 1,000 periods of the finest case keep its
#: samples in tens of MB
CYCLES = FiniteFloat(maximum=1000.0)
#: a Courant limit: beyond 100 PIMPLE's time step is limited by nothing but max_time_step
COURANT = FiniteFloat(maximum=100.0)
#: a wall-clock limit, s: at most 30 days
TIMEOUT = FiniteFloat(maximum=30 * 86400.0)
#: how many times a run writes its fields
WRITES = click.IntRange(min=1, max=100_000)

#: The identification's residual scalings (identification.fit.RESIDUAL_SCALINGS), named here
#: so that the command line does not import the fit to build its help
RESIDUAL_SCALING_NAMES = ("grid", "case")

#: ``--residual-scaling``: how a fit of the model's coefficients weighs the cases
residual_scaling_option = click.option(
    "--residual-scaling", type=click.Choice([*RESIDUAL_SCALING_NAMES, "auto"]), default=None,
    help="Residuals over each component's RMS across every case (grid: the cases of large "
         "forces weigh most), over its range in each case (case: the fit minimises the "
         "mean square NRMSE, every case weighs alike), or the one of the two that the "
         "model's errors ask for (auto: case where they grow in proportion to each run's "
         "loads); default the case file's [identification] residual_scaling, grid unless "
         "set.")


def mesh_and_setup_options(runs: str = "") -> Callable:
    """``--mesh`` and ``--setup``: the case's ``[cfd] mesh`` and ``setup`` for this command
    (:func:`cfd_settings` turns them into ``--set`` texts; the other solver settings are
    ``--set cfd.key=value``).

    Parameters
    ----------
    runs
        Which runs they apply to, for the help text (e.g. ``" of live runs"``).

    Returns
    -------
    Callable
        A decorator adding the two options.
    """
    def decorate(command):
        command = click.option(
            "--setup", "setup_name", default=None,
            help=f"A named set-up{runs} of cfd_templates/openfoam/setups.toml (mesh and "
                 "solver settings together, e.g. table1); with --mesh, its solver settings "
                 "on that mesh; other solver settings: --set cfd.KEY=VALUE. Default: the "
                 "case's [cfd] setup.",
        )(command)
        return click.option(
            "--mesh", default=None,
            help=f"Mesh{runs}, one of {MESH_NAMES} (cfd_templates/openfoam/meshes.toml); default "
                 "the case's [cfd] mesh, else the set-up's, else coarse.",
        )(command)
    return decorate


def cfd_settings(settings: Sequence[str], mesh: str | None,
                 setup_name: str | None) -> tuple[str, ...]:
    """``settings`` (the ``--set`` texts) with ``--mesh`` and ``--setup`` as
    ``cfd.mesh`` and ``cfd.setup`` after them, so that the options win.

    Examples
    --------
    >>> cfd_settings(("cfd.procs=2",), "medium", None)
    ('cfd.procs=2', 'cfd.mesh="medium"')
    """
    given = (("mesh", mesh), ("setup", setup_name))
    return (*settings, *(f"cfd.{key}={json.dumps(value)}" for key, value in given
                         if value is not None))


def set_option() -> Callable:
    """``--set table.key=value`` (repeatable): any case-file key for this run, checked like
    the file (:func:`mfflap.config.apply_settings`)."""
    return click.option(
        "--set", "settings", multiple=True, metavar="TABLE.KEY=VALUE",
        help="Set a case-file key for this run, checked like the file, e.g. "
             "--set optimisation.coefficients=case or --set rounds.count=3 (repeatable; "
             "`mfflap case show CASE_FILE --set ...` prints the result).")


def given_options(*names: str) -> list[str]:
    """The options of the running command among the parameters ``names`` that its command
    line gives, as their flags (``work_dir`` given as ``--work`` is ``"--work"``; an on/off
    flag given off, ``--no-color``, by its off flag)."""
    context = click.get_current_context()

    def flag(param: click.Parameter) -> str:
        off = getattr(param, "secondary_opts", None)
        return off[0] if off and context.params.get(param.name) is False else param.opts[0]

    flags = {param.name: flag(param) for param in context.command.params}
    return [flags[name] for name in names
            if context.get_parameter_source(name) is ParameterSource.COMMANDLINE]


def refuse_given(names: Sequence[str], apply_only: str) -> None:
    """Refuse the options among ``names`` that the command line gives where they would be
    ignored, instead of running without them.

    Parameters
    ----------
    names
        Parameter names of the running command.
    apply_only
        What they apply to and why not here, completing "--x applies only to ...".

    Raises
    ------
    click.UsageError
        Naming each option given.
    """
    given = given_options(*names)
    if given:
        verb = "applies" if len(given) == 1 else "apply"
        raise click.UsageError(f"{', '.join(given)} {verb} only to {apply_only}")


def refuse_settings(settings: Sequence[str], key: str, apply_only: str) -> None:
    """Refuse the ``--set`` texts of ``key`` (a table, or one key of it) where they would
    be ignored.

    Parameters
    ----------
    settings
        The ``--set`` texts given.
    key
        What they would set: a case-file table (``"cfd"``) or a key (``"backtest.cycles"``).
    apply_only
        What they apply to and why not here, completing "--set cfd.x applies only to ...".

    Raises
    ------
    click.UsageError
        Naming each setting given.

    Examples
    --------
    >>> refuse_settings(["backtest.average_cycles=2"], "backtest.cycles", "live runs")
    >>> refuse_settings(["cfd.procs=2"], "cfd", "live runs")
    Traceback (most recent call last):
    click.exceptions.UsageError: --set cfd.procs applies only to live runs
    """
    names = [text.split("=", 1)[0].strip() for text in settings]
    given = [name for name in names if name == key or name.startswith(f"{key}.")]
    if given:
        verb = "applies" if len(given) == 1 else "apply"
        raise click.UsageError(f"--set {', '.join(given)} {verb} only to {apply_only}")
