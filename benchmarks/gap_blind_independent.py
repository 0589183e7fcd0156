"""The gap diagnosis on hidden effects written apart from its candidate library
(:mod:`mfflap.gap.textbook_effects`), with its time.

    python benchmarks/gap_blind_independent.py [TRIALS_PER_EFFECT] [SNR]

The same as ``mfflap gap blindtest --trials N --snr X``; this prints each verdict as it
comes and the time the datasets took.
"""

from __future__ import annotations

import sys
import time

from mfflap.gap.textbook_effects import run, summary


def main() -> None:
    trials = int(sys.argv[1]) if len(sys.argv) > 1 else 3
    snr = float(sys.argv[2]) if len(sys.argv) > 2 else 3.0
    t0 = time.perf_counter()
    said = run(trials, snr, progress=print)
    print(f"\n{trials} datasets per effect at SNR {snr:g}, {time.perf_counter() - t0:.0f} s")
    print(summary(said))


if __name__ == "__main__":
    main()
