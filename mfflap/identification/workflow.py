"""Identification from folders of CFD records, for several weighting strategies, to HDF5."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from mfflap.config import CaseConfig
from mfflap.errors import MfflapError
from mfflap.identification.data import CaseData, prepare_cases
from mfflap.identification.fit import IdentificationResult, identify
from mfflap.identification.store import write_identification
from mfflap.records.inputs import check_records_inputs
from mfflap.records.record import CfdRecord, identification_fixture_dirs, read_record, read_records
from mfflap.results import ResultsFile
from mfflap.toml_io import read_toml

#: separates the record folders in an identification's ``source`` attribute
SOURCE_SEPARATOR = "\n"


def failed_cases(folder: str | Path) -> dict[str, str]:
    """Cases whose CFD failed in a campaign (or back-test) folder, with the reason: named by
    the file's ``case_id``, else by its file name without ``.failed.toml`` (a back-test's
    failure file has no case id)."""
    out = {}
    for p in sorted(Path(folder).glob("*.failed.toml")):
        info = read_toml(p)
        name = info.get("case_id", p.name.removesuffix(".failed.toml"))
        out[str(name)] = f"CFD failed: {info.get('error', '')}"
    return out


def _folder_list(folders: str | Path | Sequence[str | Path] | None) -> list[Path]:
    if folders is None:
        folders = []
    elif isinstance(folders, (str, Path)):
        folders = [f for f in str(folders).split(SOURCE_SEPARATOR) if f]
    return [Path(f) for f in folders] or list(identification_fixture_dirs())


def source_text(folders: Sequence[str | Path]) -> str:
    """The record folders as stored in a result's ``source`` attribute (one per line)."""
    return SOURCE_SEPARATOR.join(str(f) for f in folders)


def sources_shown(folders: str | Path | Sequence[str | Path] | None) -> str:
    """The record folders or files that :func:`pooled_records` reads, comma-separated, for
    messages and reports (the shipped fixtures if none are given)."""
    return ", ".join(str(f) for f in _folder_list(folders))


def pooled_records(folders: str | Path | Sequence[str | Path] | None = None,
                   config: CaseConfig | None = None, use: str = "identification"
                   ) -> tuple[list[CfdRecord], dict[str, str]]:
    """The records of one or more folders or record files (the shipped fixtures by default),
    and the cases that failed in a folder without a record anywhere else, with the reason.

    Several folders pool their records, so that a campaign's gaps can be filled from
    another (a case its set-up lost, rerun with another); a record file (``DIR/CASE.h5``)
    adds that record alone, so that a few cases can be taken from a folder that also holds
    others. A string holding several paths one per line (a result's ``source``,
    :func:`source_text`) is read as those paths. Given ``config``, the records must have
    been run for its plate, fluid and stream (:mod:`mfflap.records.inputs`); ``use``
    says what for, in the refusal.

    Raises
    ------
    MfflapError
        If a case has a record in two of the paths (which CFD to use is ambiguous), naming
        both, or if the paths hold no record.
    ConfigError
        If a record was run for another plate, fluid or stream than ``config``'s.
    """
    paths = _folder_list(folders)
    records, origin, failed = [], {}, {}
    for path in paths:
        if path.is_file():
            found = [read_record(path)]
        else:
            found = read_records(path)
            for name, why in failed_cases(path).items():
                failed.setdefault(name, f"{why} ({path})")
        for rec in found:
            if rec.name in origin:
                raise MfflapError(
                    f"case {rec.name} has a record in {origin[rec.name]} and in {path}: "
                    "keep one so that it is clear which CFD to use (give the record files "
                    "wanted from one folder, DIR/CASE.h5, instead of the folder)")
            origin[rec.name] = path
            records.append(rec)
    if not records:
        where = ", ".join(str(f) for f in paths)
        raise MfflapError(f"{where}: no CFD records (*.h5); run "
                          "`mfflap campaign run` into it or point --fixtures elsewhere")
    if config is not None:
        check_records_inputs([(r, origin[r.name]) for r in records], config.plate,
                             config.fluid, config.flow, case_source=config.source, use=use)
    return records, {k: v for k, v in failed.items() if k not in origin}


def load_cases(config: CaseConfig,
               folders: str | Path | Sequence[str | Path] | None = None,
               n_samples: int = 400) -> tuple[list[CaseData], dict[str, str]]:
    """Prepared cases of one or more record folders (:func:`pooled_records`) and the cases
    left out, with the reason (a failed run, a record identification cannot use)."""
    records, failed = pooled_records(folders, config)
    cases, excluded = prepare_cases(records, config.identification.discard_time, n_samples,
                                    plate=config.plate, fluid=config.fluid,
                                    stream=config.flow)
    excluded.update(failed)
    return cases, excluded


def leave_out(cases: Sequence[CaseData], excluded: dict[str, str],
              names: Sequence[str]) -> tuple[list[CaseData], dict[str, str]]:
    """``cases`` without those named (a case to refit without, e.g. the one a coefficient
    rests on most), each added to ``excluded`` with the reason.

    Raises
    ------
    MfflapError
        For a name that is none of the cases, with the names there are.
    """
    have = {c.name for c in cases}
    unknown = [n for n in names if n not in have]
    if unknown:
        raise MfflapError(f"no case {', '.join(map(repr, unknown))} among the "
                          f"{len(have)} to identify from: {', '.join(sorted(have))}")
    drop = set(names)
    kept = [c for c in cases if c.name not in drop]
    return kept, {**excluded, **{n: "left out on request (--exclude)" for n in names}}


def identify_strategies(config: CaseConfig, cases: Sequence[CaseData],
                        excluded: dict[str, str], strategies: Sequence[str | Sequence[float]],
                        components: Sequence[str] | None = None,
                        n_bootstrap: int = 200,
                        residual_scaling: str | None = None) -> dict[str, IdentificationResult]:
    """One identification per strategy (the case's frequency_weights count as ``custom``),
    with the case's ``[identification] residual_scaling`` unless another is given."""
    base = config.morison_model()
    scaling = residual_scaling or config.identification.residual_scaling
    out = {}
    for strategy in strategies:
        kwargs = {} if components is None else {"components": tuple(components)}
        res = identify(cases, base, strategy, n_bootstrap=n_bootstrap, excluded=excluded,
                       residual_scaling=scaling, **kwargs)
        out[res.strategy] = res
    return out


def save_identification(path: str | Path, config: CaseConfig,
                        results: dict[str, IdentificationResult], source: str) -> Path:
    """Write every strategy's result with the case configuration beside it."""
    path = Path(path)
    with ResultsFile(path, "w", kind="identification", config_toml=config.to_toml()) as rf:
        for res in results.values():
            write_identification(rf, res)
        rf.h5["identification"].attrs["source"] = source
    return path
