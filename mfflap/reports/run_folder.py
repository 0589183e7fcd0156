"""The output folder of ``mfflap run``: what a run writes there, and a clean start for the
next one.

A run writes its report, its results and its motions for ParaView into one folder. A second
run into the same folder would overwrite the first run's report and results and leave the
first run's motion files beside its own, so :func:`prepare_run_folder` refuses a folder that
holds a run's outputs unless told to overwrite it, and then removes them first. The CFD a
run did there (the live back-tests' case folders and records) is kept: a rerun finds those
records and resumes those cases instead of running them again.

Examples
--------
>>> import tempfile
>>> from pathlib import Path
>>> folder = Path(tempfile.mkdtemp()) / "study_run"
>>> prepare_run_folder(folder, overwrite=False).is_dir()
True
>>> _ = (folder / "report.html").write_text("<html></html>")
>>> prepare_run_folder(folder, overwrite=False)  # doctest: +ELLIPSIS
Traceback (most recent call last):
...
mfflap.errors.OutputExistsError: ...study_run: holds another run's outputs (report.html); ...
>>> _ = prepare_run_folder(folder, overwrite=True)
>>> sorted(p.name for p in folder.iterdir())
[]
"""

from __future__ import annotations

import re
import shutil
from pathlib import Path

from mfflap.errors import OutputExistsError

#: the files and folders a run writes (``mfflap run``, and ``[rounds]`` in the loop)
RUN_OUTPUT_FILES = ("report.html", "results.h5", "rounds.html", "rounds.h5", "rounds.png")
RUN_OUTPUT_FOLDERS = ("vtk",)
#: a round's own folder of outputs (``round_<k>``)
ROUND_FOLDER = re.compile(r"round_\d+")
#: what a rerun keeps: the CFD it did (live back-test case folders and records)
KEPT_CFD = ("cfd_cases", "backtest_records", "loop_records")


def run_outputs_in(folder: Path) -> tuple[str, ...]:
    """The names of a run's outputs in ``folder``, sorted (none if it does not exist)."""
    if not folder.is_dir():
        return ()
    return tuple(sorted(
        p.name for p in folder.iterdir()
        if (p.name in RUN_OUTPUT_FILES and (p.is_file() or p.is_symlink()))
        or (p.is_dir() and not p.is_symlink()
            and (p.name in RUN_OUTPUT_FOLDERS or ROUND_FOLDER.fullmatch(p.name)))))


def prepare_run_folder(folder: Path, *, overwrite: bool) -> Path:
    """Make ``folder`` ready for a run's outputs and return it.

    Parameters
    ----------
    folder
        The run's output folder; created if missing.
    overwrite
        If the folder holds another run's outputs (:func:`run_outputs_in`): False refuses it,
        True removes those outputs first. Other files, and the CFD of the earlier run
        (:data:`KEPT_CFD`), are never removed.

    Raises
    ------
    OutputExistsError
        The folder holds another run's outputs and ``overwrite`` is False, or the folder, or
        a name the run writes in it, is a symbolic link (outputs never follow a link out of
        the folder).
    """
    if folder.is_symlink():
        raise OutputExistsError("is a symbolic link; a run writes into a folder of its own, "
                                "not through a link", path=str(folder))
    linked = tuple(sorted(name for name in (*RUN_OUTPUT_FILES, *RUN_OUTPUT_FOLDERS, *KEPT_CFD)
                          if (folder / name).is_symlink()))
    if linked:
        raise OutputExistsError(f"holds symbolic links where the run writes its outputs "
                                f"({', '.join(linked)}); outputs are never written through a "
                                "link: remove them, or choose another --out",
                                path=str(folder), held=linked)
    held = run_outputs_in(folder)
    if held and not overwrite:
        raise OutputExistsError(
            f"holds another run's outputs ({', '.join(held)}); choose another --out, or give "
            "--overwrite to replace them (its CFD records and case folders are kept and "
            "reused)", path=str(folder), held=held)
    for name in held:
        path = folder / name
        if path.is_dir() and not path.is_symlink():
            shutil.rmtree(path)
        else:
            path.unlink()
    folder.mkdir(parents=True, exist_ok=True)
    return folder
