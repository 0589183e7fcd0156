"""Run an OpenFOAM case: blockMesh, checkMesh, pimpleFoam, with a timeout and divergence
detection. Logs are kept in the case folder (log.<application>)."""

from __future__ import annotations

import os
import re
import shutil
import subprocess
from pathlib import Path

from mfflap.errors import CfdRunError

# Crash and divergence signatures (not the banner's "Floating point exception trapping
# enabled"): NaN residuals, the sigFpe handler's stack trace, fatal errors.
_DIVERGED = re.compile(
    r"((?<![A-Za-z])-?nan(?![A-Za-z])|sigFpe::sigHandler|Floating point exception \(core|"
    r"FOAM FATAL)",
    re.I,
)
_COURANT = re.compile(r"Courant Number mean: \S+ max: ([-+0-9.eE]+)\s")


def openfoam_available() -> bool:
    """True if the OpenFOAM solvers are on PATH."""
    return shutil.which("pimpleFoam") is not None and shutil.which("blockMesh") is not None


def _env() -> dict[str, str]:
    env = dict(os.environ)
    env.setdefault("WM_PROJECT_DIR", "/usr/share/openfoam")
    return env


def max_courant(log_text: str) -> float:
    """Largest maximum Courant number reported in a pimpleFoam log (0 if none)."""
    return max((float(c) for c in _COURANT.findall(log_text)), default=0.0)


def _tail(path: Path, n: int = 20) -> str:
    if not path.exists():
        return ""
    return "\n".join(path.read_text(errors="replace").splitlines()[-n:])


def run_application(case_dir: str | Path, application: str, timeout_s: float = 3600.0,
                    max_courant_abort: float = 100.0, n_procs: int = 1,
                    extra_args: tuple[str, ...] = ()) -> Path:
    """Run one OpenFOAM application in a case; return the log path.

    Raises
    ------
    CfdRunError
        On a non-zero exit, a timeout, NaNs or a floating-point exception in the log, or a
        Courant number above ``max_courant_abort`` (an exploding run), with the log's tail.
    """
    case_dir = Path(case_dir)
    if not openfoam_available():
        raise CfdRunError("OpenFOAM is not installed (apt-get install openfoam)",
                          case=str(case_dir))
    log = case_dir / f"log.{application}"
    with open(log, "a") as fh:
        try:
            command = [application, "-case", str(case_dir), *extra_args]
            if n_procs > 1:
                command = ["mpirun", "-np", str(n_procs), "--allow-run-as-root",
                           "--oversubscribe", *command, "-parallel"]
            proc = subprocess.run(command, stdout=fh,
                                  stderr=subprocess.STDOUT, timeout=timeout_s, env=_env(),
                                  check=False)
        except subprocess.TimeoutExpired as exc:
            raise CfdRunError(f"{application} timed out after {timeout_s} s", case=str(case_dir),
                              log_tail=_tail(log)) from exc
    text = log.read_text(errors="replace")
    courants = max_courant(text[-200_000:])
    if proc.returncode != 0 or _DIVERGED.search(text[-50_000:]):
        raise CfdRunError(f"{application} failed (exit code {proc.returncode}, diverged or "
                          "crashed)", case=str(case_dir), log_tail=_tail(log))
    if courants > max_courant_abort:
        raise CfdRunError(f"Courant number exploded to {courants:g}", case=str(case_dir),
                          log_tail=_tail(log))
    return log


def run_case(case_dir: str | Path, timeout_s: float = 3600.0, n_procs: int = 1) -> None:
    """blockMesh (once), checkMesh (once), then pimpleFoam from the latest written time.

    With ``n_procs`` > 1 the case is decomposed once (``method simple``: scotch and metis are
    stubs in Debian's package) and pimpleFoam runs under mpirun; a restart continues from the
    processor folders' latest time. The forces function object writes from the master.
    """
    case_dir = Path(case_dir)
    if not (case_dir / "constant" / "polyMesh" / "points").exists():
        run_application(case_dir, "blockMesh", timeout_s=300)
        log = run_application(case_dir, "checkMesh", timeout_s=300)
        if "Mesh OK" not in log.read_text():
            raise CfdRunError("checkMesh did not report 'Mesh OK'", case=str(case_dir),
                              log_tail=_tail(log))
    if n_procs > 1:
        dict_path = case_dir / "system" / "decomposeParDict"
        text = dict_path.read_text()
        text = re.sub(r"numberOfSubdomains\s+\d+;", f"numberOfSubdomains {n_procs};", text)
        text = re.sub(r"n\s+\(\d+ 1 1\);", f"n           ({n_procs} 1 1);", text)
        dict_path.write_text(text)
        if not (case_dir / "processor0").exists():
            run_application(case_dir, "decomposePar", timeout_s=300)
    run_application(case_dir, "pimpleFoam", timeout_s=timeout_s, n_procs=n_procs)
