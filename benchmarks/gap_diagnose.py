"""Cost of a gap diagnosis of one external dataset: 36 cases of 600 samples each, read from a
folder of CSV runs with their rates and a manifest, then diagnosed with the case file's
defaults; against one identification of the Morison model on the same cases, timed in the
same process.

Run: python benchmarks/gap_diagnose.py
"""

from __future__ import annotations

import tempfile
from pathlib import Path

import numpy as np
from timing import best_of

from mfflap.config import load_case
from mfflap.gap.blindtest import ar1_noise, trial_cases
from mfflap.gap.manifest import read_dataset
from mfflap.gap.workflow import diagnose_cases
from mfflap.identification.fit import identify

CASE = Path(__file__).parents[1] / "cases" / "paper2026.toml"
HEADER = ("time,pitch_angle,heave_position,normal_force,tangential_force,moment,pitch_rate,"
          "pitch_acceleration,heave_velocity,heave_acceleration")


def write_dataset(folder: Path, n_cases: int = 36, n_samples: int = 600) -> None:
    """The Morison model's loads plus 5 % AR(1) noise on random ramp motions, as CSV runs
    with all four rate columns and a manifest."""
    config = load_case(CASE)
    rng = np.random.default_rng(0)
    model = config.morison_model()
    lines = ["[setup]", f"velocity = {config.flow.velocity}", ""]
    for i, case in enumerate(trial_cases(rng, n_cases, n_samples)):
        s, loads = case.state, model.loads(case.state)
        noisy = [y + 0.05 * np.std(y) * ar1_noise(rng, len(y))
                 for y in (loads.normal_force, loads.tangential_force, loads.moment)]
        columns = [s.time, s.pitch_angle, s.heave_position, *noisy, s.pitch_rate,
                   s.pitch_acceleration, s.heave_velocity, s.heave_acceleration]
        np.savetxt(folder / f"run{i:02d}.csv", np.column_stack(columns), delimiter=",",
                   header=HEADER, comments="")
        lines += ["[[run]]", f'file = "run{i:02d}.csv"',
                  f"frequency = {case.parameters['frequency']}",
                  f"heave_amplitude = {case.parameters['heave_amplitude']}", ""]
    (folder / "manifest.toml").write_text("\n".join(lines))


def main() -> None:
    config = load_case(CASE)
    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        write_dataset(folder)
        cases = read_dataset(folder, config=config)
        model = config.morison_model()
        base = best_of(lambda: identify(cases, model, n_bootstrap=0), repeat=3)
        read = best_of(lambda: read_dataset(folder, config=config), repeat=3)
        diagnosis = best_of(lambda: diagnose_cases(config, cases), repeat=3)
        finding = diagnose_cases(config, cases)[0].finding
    print(f"{len(cases)} cases x {len(cases[0].state.time)} samples ({finding})")
    print("step                          time [s]   / one identification")
    for label, t in (("one identification (baseline)", base), ("read folder + manifest", read),
                     ("gap diagnosis", diagnosis), ("read + diagnosis", read + diagnosis)):
        print(f"{label:29s} {t:9.3f}   {t / base:8.1f}")
    print(f"goal: read + diagnosis under 2 s: {'met' if read + diagnosis < 2.0 else 'not met'}")


if __name__ == "__main__":
    main()
