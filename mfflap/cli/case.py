"""``mfflap init`` (a commented case file to start from) and ``mfflap case show`` (a case
file as mfflap reads it, every default marked)."""

from __future__ import annotations

from pathlib import Path

import click

from mfflap.cli.options import set_option


@click.command("init")
@click.argument("case_file", type=click.Path(dir_okay=False, path_type=Path))
@click.option("--name", default=None,
              help="The study's name (default: the file's name without .toml).")
def init(case_file: Path, name: str | None) -> None:
    """Write a case file holding every key with the paper's values and a comment on each
    (unit, allowed values, meaning). An existing file is not written over."""
    import dataclasses

    from mfflap.config import CaseConfig, StudyInfo
    from mfflap.config_reference import commented_case_toml

    if case_file.exists():
        raise click.BadParameter(f"{case_file} exists; give a new file",
                                 param_hint="CASE_FILE")
    config = dataclasses.replace(CaseConfig(), study=StudyInfo(name or case_file.stem))
    case_file.parent.mkdir(parents=True, exist_ok=True)
    case_file.write_text(commented_case_toml(config))
    click.echo(f"wrote {case_file}: edit it, then `mfflap evaluate {case_file}`")


@click.group("case")
def case() -> None:
    """Case files."""


@case.command("show")
@click.argument("case_file", type=click.Path(dir_okay=False, exists=True, path_type=Path))
@set_option()
def show(case_file: Path, settings: tuple[str, ...]) -> None:
    """Print CASE_FILE as mfflap reads it, with any --set applied: every key with its
    value, those neither the file nor --set gives marked (default)."""
    from mfflap.config import apply_settings, load_case
    from mfflap.config_reference import commented_case_toml
    from mfflap.toml_io import read_toml

    config = load_case(case_file, settings)
    given = apply_settings(read_toml(case_file), settings)
    click.echo(commented_case_toml(config, given=given), nl=False)


__all__ = ["case", "init"]
