"""Where the main job's time goes: `mfflap run cases/paper2026.toml` split into the import
of the command line, each stage of the study, the HDF5 results file and the HTML report,
each printed in seconds and as a share of the whole; then the whole command run again in a
fresh process, the baseline the parts are a share of.

    python benchmarks/main_job.py [CASE_FILE]

Run it on an idle machine: a CFD campaign beside it slows every part.
"""

from __future__ import annotations

import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def main() -> None:
    case_file = Path(sys.argv[1]) if len(sys.argv) > 1 else ROOT / "cases" / "paper2026.toml"
    out = Path(tempfile.mkdtemp())
    t0 = time.perf_counter()
    from mfflap.cli.main import cli  # noqa: F401  (the import a command pays)

    imported = time.perf_counter() - t0
    from mfflap.config import load_case
    from mfflap.identification.workflow import sources_shown
    from mfflap.pipeline import RunOptions, run_study, write_results
    from mfflap.reports.run import write_run_report

    case = load_case(case_file)
    t1 = time.perf_counter()
    outcome = run_study(case, RunOptions.for_case(case, out), progress=lambda _: None)
    stages = time.perf_counter() - t1
    t2 = time.perf_counter()
    write_results(outcome.config or case, outcome, out / "results.h5")
    written = time.perf_counter() - t2
    t3 = time.perf_counter()
    write_run_report(outcome.config or case, outcome, out / "report.html", sources_shown(()))
    reported = time.perf_counter() - t3
    in_process = time.perf_counter() - t0

    t4 = time.perf_counter()
    subprocess.run([sys.executable, "-c", "from mfflap.cli.main import cli; cli()", "run",
                    str(case_file), "--out", str(out / "whole")], check=True,
                   capture_output=True)
    whole = time.perf_counter() - t4

    rows = [("import mfflap.cli.main", imported), ("study stages (all)", stages),
            *((f"  {name}", seconds) for name, seconds in outcome.timings.items()),
            ("results file (HDF5)", written), ("report (HTML, figures)", reported),
            ("the parts in one process", in_process),
            ("mfflap run in a fresh process (baseline)", whole)]
    print(f"{'part':44s} {'s':>7s} {'share of baseline':>18s}")
    for name, seconds in rows:
        print(f"{name:44s} {seconds:7.2f} {seconds / whole:18.2f}")
    print(f"the rest of a fresh process (interpreter, loading the compiled kernels, the "
          f"click layer): {whole - in_process:.2f} s, {(whole - in_process) / whole:.2f}")


if __name__ == "__main__":
    main()
