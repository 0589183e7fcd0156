"""A series of rounds of the shipped case with the phase fixed, run in a process of its own
on other BLAS arithmetic than the shipped series were computed with (the tests of the
optimisation's phase and the replays of the findings pages share it)."""

import json
import os
import subprocess
import sys
from pathlib import Path

from openblas_kernels import cpu_flags
from shipped_settings import as_shipped

CASE = Path(__file__).parents[1] / "cases" / "paper2026.toml"


def fixed_phase_series(out: Path, n_rounds: int, *flags: str, haswell: bool = False
                       ) -> tuple[dict, str]:
    """`mfflap run` of the shipped case in ``n_rounds`` rounds with the phase fixed, the
    output correction without a refit and ``flags`` (``--set`` pairs), on one OpenBLAS
    thread (the shipped series ran on two) and, with ``haswell``, OpenBLAS's Haswell kernels
    where the CPU has AVX2 (the shipped series ran on SkylakeX's). Its rounds summary and
    its stderr."""
    env = {k: v for k, v in os.environ.items() if k != "OPENBLAS_CORETYPE" or not haswell}
    env["OPENBLAS_NUM_THREADS"] = "1"
    if haswell and "avx2" in cpu_flags():
        env["OPENBLAS_CORETYPE"] = "Haswell"
    proc = subprocess.run(
        [sys.executable, "-c", "from mfflap.cli.main import cli; cli()", "run", str(CASE),
         "--out", str(out), *as_shipped(
             "--set", f"rounds.count={n_rounds}", "--set", "optimisation.coefficients=uniform",
             "--set", "optimisation.within_data=true", "--set", "rounds.correct_outputs=true",
             "--set", "rounds.refit=false", *flags, "--set", "optimisation.ipopt=false",
             "--set", "optimisation.gain_table=false", "--set", "optimisation.phase=fixed"),
         "--json"],
        env=env, capture_output=True, text=True, timeout=1800)
    assert proc.returncode == 0, proc.stderr[-3000:]
    return json.loads(proc.stdout[proc.stdout.index("{"):])["rounds"], proc.stderr
