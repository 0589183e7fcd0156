"""Test helpers for Fluent's side, shared by the tests of several packages: a generated
UDF compiled with gcc against the stand-in header and run in a C test program, and report
files written as Fluent writes them."""

import shutil
import subprocess
from pathlib import Path

import numpy as np

from mfflap.cfd.fluent.udf import standin_header_dir

GCC = shutil.which("gcc")

MAIN = r"""
#include "udf.h"
#include <stdlib.h>
void mfflap_motion(Dynamic_Thread *dt, real vel[], real omega[], real time, real dtime);
int main(int argc, char **argv)
{
    int i;
    real vel[ND_ND], omega[3];
    for (i = 1; i < argc; i++) {
        real t = atof(argv[i]);
        mfflap_motion(NULL, vel, omega, t, 1e-3);
        printf("%.17g %.17g %.17g %.17g\n", (double)vel[0], (double)vel[1], (double)omega[2],
               (double)omega[0]);
    }
    return 0;
}
"""


def compile_syntax(source: str, tmp_path: Path, nd: int) -> None:
    assert GCC, "gcc must be installed (.ci/run installs it)"
    src = tmp_path / f"udf_{nd}.c"
    src.write_text(source)
    subprocess.run([GCC, "-fsyntax-only", "-Wall", "-Wextra", "-Werror",
                    "-Wno-unused-parameter", f"-DND_ND={nd}", "-I", str(standin_header_dir()),
                    str(src)], check=True, capture_output=True, text=True)


def run_udf(source: str, tmp_path: Path, times: np.ndarray, nd: int = 2) -> np.ndarray:
    assert GCC, "gcc must be installed (.ci/run installs it)"
    (tmp_path / "udf.c").write_text(source)
    (tmp_path / "main.c").write_text(MAIN)
    exe = tmp_path / "udf_test"
    subprocess.run([GCC, "-O1", "-Wall", "-Werror", "-Wno-unused-parameter", f"-DND_ND={nd}",
                    "-I", str(standin_header_dir()), str(tmp_path / "udf.c"),
                    str(tmp_path / "main.c"), "-lm", "-o", str(exe)], check=True,
                   capture_output=True, text=True)
    out = subprocess.run([str(exe), *[repr(float(t)) for t in times]], check=True,
                         capture_output=True, text=True).stdout
    return np.array([[float(v) for v in line.split()] for line in out.splitlines()])


HEADER = '"plate-forces"\n"Time Step" "fx-plate fy-plate etc.."\n'


def report_text(names, rows):
    head = HEADER + "(" + " ".join(f'"{n}"' for n in names) + ")\n"
    return head + "\n".join(" ".join(repr(float(v)) for v in r) for r in rows) + "\n"


def write_plate_report(path: Path, t, fx, fy, mz) -> Path:
    """A Fluent report file of the plate's force and moment columns at flow times t."""
    rows = np.column_stack([np.arange(len(t)), fx, fy, mz, t])
    path.write_text(report_text(["Time Step", "fx-plate", "fy-plate", "mz-plate",
                                 "flow-time"], rows))
    return path
