"""Identification from a folder of CFD records, for several weighting strategies, to HDF5."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from mfflap.campaign.records import fixture_dir, read_records
from mfflap.config import CaseConfig
from mfflap.identification.data import CaseData, prepare_cases
from mfflap.identification.fit import IdentificationResult, identify
from mfflap.identification.store import write_identification
from mfflap.results import ResultsFile
from mfflap.toml_io import read_toml


def failed_cases(folder: str | Path) -> dict[str, str]:
    """Cases whose CFD failed in a campaign folder, with the reason."""
    out = {}
    for p in sorted(Path(folder).glob("*.failed.toml")):
        info = read_toml(p)
        out[str(info.get("case_id", p.stem))] = f"CFD failed: {info.get('error', '')}"
    return out


def load_cases(config: CaseConfig, folder: str | Path | None = None,
               n_samples: int = 400) -> tuple[list[CaseData], dict[str, str]]:
    """Prepared cases of a record folder (the shipped fixtures by default) and the excluded."""
    folder = Path(folder) if folder is not None else fixture_dir()
    records = read_records(folder)
    if not records:
        from mfflap.errors import MfflapError

        raise MfflapError(f"{folder}: no CFD records (*.h5) to identify from; run "
                          "`mfflap campaign run` into it or point --fixtures elsewhere")
    cases, excluded = prepare_cases(records, config.identification.discard_time, n_samples,
                                    plate=config.plate, fluid=config.fluid,
                                    stream=config.flow)
    excluded.update(failed_cases(folder))
    return cases, excluded


def identify_strategies(config: CaseConfig, cases: Sequence[CaseData],
                        excluded: dict[str, str], strategies: Sequence[str | Sequence[float]],
                        components: Sequence[str] | None = None,
                        n_bootstrap: int = 200) -> dict[str, IdentificationResult]:
    """One identification per strategy (the case's frequency_weights count as ``custom``)."""
    base = config.morison_model()
    out = {}
    for strategy in strategies:
        kwargs = {} if components is None else {"components": tuple(components)}
        res = identify(cases, base, strategy, n_bootstrap=n_bootstrap, excluded=excluded,
                       **kwargs)
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
