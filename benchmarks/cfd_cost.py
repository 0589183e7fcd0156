"""CPU per flapping cycle on each mesh, and NRMSE of the forces against the medium mesh.

f = 1 Hz, h_amp = 0.3 m, theta = 20 deg, phi = 90 deg, with a 0.25 s smooth start-up ramp.
The comparison uses the second simulated cycle. Run: python benchmarks/cfd_cost.py [cycles]
Meshes run two at a time (two cores). Prints ratios against the medium mesh.
"""

from __future__ import annotations

import resource
import sys
import tempfile
import time
from concurrent.futures import ProcessPoolExecutor
from pathlib import Path

import numpy as np

from mfflap.cfd.openfoam.forces import read_forces
from mfflap.cfd.openfoam.loads import imposed_state, to_loads
from mfflap.cfd.openfoam.runner import run_case
from mfflap.cfd.openfoam.writer import write_case
from mfflap.kinematics import HarmonicMotion
from mfflap.metrics import nrmse

MOTION = HarmonicMotion(1.0, 0.3, np.deg2rad(20), np.pi / 2)


def run_mesh(args):
    mesh, root, cycles = args
    case = write_case(Path(root) / mesh, MOTION, end_time=cycles, mesh=mesh, ramp_time=0.25)
    t0 = time.process_time()
    r0 = resource.getrusage(resource.RUSAGE_CHILDREN)
    run_case(case, timeout_s=7200)
    r1 = resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime) + time.process_time() - t0
    h = read_forces(case)
    st = imposed_state(MOTION, h.time, 0.25)
    loads = to_loads(h, st, 0.18, 0.18, mesh)
    return mesh, cpu / cycles, h.time, loads.normal_force, loads.tangential_force


def main() -> None:
    cycles = float(sys.argv[1]) if len(sys.argv) > 1 else 2.0
    root = tempfile.mkdtemp(prefix="mfflap-cfd-cost-")
    meshes = ["coarse", "medium"]
    with ProcessPoolExecutor(2) as pool:
        results = {r[0]: r for r in pool.map(run_mesh, [(m, root, cycles) for m in meshes])}
    t = np.linspace(cycles - 1.0, cycles, 400)
    ref = results["medium"]
    ref_fn = np.interp(t, ref[2], ref[3])
    for mesh in meshes:
        _, cpu, tt, fn, _ = results[mesh]
        err = nrmse(np.interp(t, tt, fn), ref_fn)
        print(f"{mesh:8s} CPU per cycle {cpu:8.1f} s  ratio to medium {cpu / ref[1]:.3f}  "
              f"F_n NRMSE vs medium (last cycle) {100 * err:.2f} %")


if __name__ == "__main__":
    main()
