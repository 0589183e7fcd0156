"""TimeStepWatch: every time step of a growing solver log is judged once, from real logs."""

import re
import tempfile
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from mfflap.cfd.openfoam.time_step_watch import TimeStepWatch

DATA = Path(__file__).parents[2] / "data" / "openfoam_v1912"
#: 634 lines of a real coarse-mesh back-test (the fixed-phase first-order series,
#: round 4, beta = 0, after its first retry): the time step falls from 2.3e-6 s to 3.2e-8 s
#: at t = 4.3245 s and recovers to 2.1e-7 s within 0.8 s of CPU time (ExecutionTime 14.26 to
#: 15.03 s). A watch that read only the log's last time step every 2 s missed it; the run
#: went on to its end with forces near 1e9 N and the time 4.3245473 s written twice.
BRIEF = (DATA / "brief_collapse.log").read_bytes()


def _grown(path: Path, text: bytes, cuts: list[int], watch: TimeStepWatch) -> list:
    """Write ``text`` to ``path`` in pieces cut at ``cuts``, reading after each piece as the
    runner's poll does, and read to the end after the last (the solver has exited)."""
    seen, done = [], 0
    with open(path, "ab") as fh:
        for cut in sorted(cuts):
            fh.write(text[done:cut])
            fh.flush()
            done = max(done, cut)
            seen.append(watch.read())
        fh.write(text[done:])
    seen.append(watch.read(to_end=True))
    return seen


@settings(max_examples=60, deadline=None)
@given(st.lists(st.integers(0, len(BRIEF)), max_size=12))
def test_a_brief_real_collapse_is_seen_wherever_the_polls_fall(cuts):
    """Cut anywhere (mid-number included) and read between the pieces, the log gives the
    first step below 1e-7 s and the time it reached, as the whole log read at once does."""
    with tempfile.TemporaryDirectory() as folder:
        log = Path(folder) / "log.pimpleFoam"
        watch = TimeStepWatch(log, 1e-7)
        seen = _grown(log, BRIEF, cuts, watch)
    assert seen[-1] == (6.1374284e-08, 4.3245473)
    assert watch.smallest_time_step_s == 3.1697011e-08
    # the Courant number stayed bounded (the adaptive time step held it): 10.7 at most
    assert watch.largest_courant == (10.720501, 4.3245465)
    # once seen, a collapse stays: a later poll does not clear it
    first = next(i for i, found in enumerate(seen) if found is not None)
    assert all(found == seen[-1] for found in seen[first:])


def test_the_last_time_step_alone_misses_the_real_collapse():
    """Why every line is read: at the excerpt's end the last time step is above 1e-7 s again,
    and so is every poll's last one that falls after the recovery."""
    steps = [float(s) for s in re.findall(rb"^deltaT = (\S+)", BRIEF, re.M)]
    below = [i for i, step in enumerate(steps) if step < 1e-7]
    assert steps[-1] >= 1e-7 and below and below[-1] < len(steps) - 1
    assert TimeStepWatch(DATA / "brief_collapse.log", 1e-7).read() == (6.1374284e-08, 4.3245473)
    assert TimeStepWatch(DATA / "brief_collapse.log", 3e-8).read() is None


def test_a_half_written_number_waits_for_the_rest_of_its_line(tmp_path):
    """'deltaT = 0.000' is the start of 0.00012, not a step of 0 s: a line without its
    newline is read only when its newline is written, or once the solver has exited."""
    log = tmp_path / "log.pimpleFoam"
    watch = TimeStepWatch(log, 1e-7)
    assert watch.read() is None  # no log yet
    log.write_bytes(b"Time = 0\n\nCourant Number mean: 0 max: 0\ndeltaT = 0.000")
    assert watch.read() is None
    with open(log, "ab") as fh:
        fh.write(b"12\nTime = 0.00012\n\ndeltaT = 5e-0")
    assert watch.read() is None and watch.smallest_time_step_s == 0.00012
    with open(log, "ab") as fh:
        fh.write(b"9")  # the solver exits before it ends the line
    assert watch.read() is None
    assert watch.read(to_end=True) == (5e-09, 0.00012)  # the time before it: none after


def test_a_collapse_above_where_the_run_began_is_an_earlier_runs(tmp_path):
    """A rerun appends to its case's log: the collapsed run above it (a real v1912 tail whose
    time step went to 7e-26 s at t = 1.3821858 s) is not this run's."""
    earlier = (DATA / "collapsed_dt.log").read_bytes()
    log = tmp_path / "log.pimpleFoam"
    log.write_bytes(earlier + b"Courant Number mean: 0 max: 0.1\ndeltaT = 0.00012\n"
                    b"Time = 0.00012\n")
    assert TimeStepWatch(log, 1e-9, start_byte=len(earlier)).read() is None
    assert TimeStepWatch(log, 1e-9).read() == (pytest.approx(7.3628536e-26), 1.3821858)


def test_lines_that_only_look_like_steps_are_not_judged(tmp_path):
    """A garbled number, a time line with more on it (tabulatedAccelerationSource's), a
    deltaT inside another line: none is a time step."""
    log = tmp_path / "log.pimpleFoam"
    log.write_bytes(b"deltaT = 1.2.3e-9\nTime = 0.5 accelerations: (0 0 0)\n"
                    b"  deltaT = 1e-12\nmaxDeltaT = 1e-12\ndeltaT = 2e-4\nTime = 0.5002\n")
    watch = TimeStepWatch(log, 1e-7)
    assert watch.read(to_end=True) is None and watch.smallest_time_step_s == 2e-4
