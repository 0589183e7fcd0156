"""Records and results files are written whole or not at all: an edit killed at any of its
writes leaves the record as it was, a temporary file of a writer still at work is never
removed by another process, and a new content removed before it could take the file's place
is an error, not a silent success."""

from __future__ import annotations

import hashlib
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from mfflap.atomic_write import stale_temporaries, temporary_beside
from mfflap.campaign.cases import CfdCase
from mfflap.campaign.execute import CampaignSetup, run_campaign
from mfflap.errors import MfflapError
from mfflap.records.cycle_scatter import add_cycle_scatter, read_cycle_scatter
from mfflap.records.record import read_record
from mfflap.results import ResultsFile

SHIPPED = (Path(__file__).parents[2] / "data" / "mfflap_data" / "fixtures" / "harmonic_set"
           / "harmonic_f1p000_h0p0500_th30p00_phi060p0.h5")

#: runs add_cycle_scatter on argv[1], killing the process (SIGKILL) at the argv[2]-th
#: write of an HDF5 attribute or group, or counting the writes with argv[2] = 0
_KILL_AT_WRITE = """
import os, signal, sys
import h5py
from mfflap.records.cycle_scatter import add_cycle_scatter
path, kill_at = sys.argv[1], int(sys.argv[2])
writes = 0
def counted(original):
    def write(*args, **kwargs):
        global writes
        writes += 1
        if writes == kill_at:
            os.kill(os.getpid(), signal.SIGKILL)
        return original(*args, **kwargs)
    return write
h5py.AttributeManager.__setitem__ = counted(h5py.AttributeManager.__setitem__)
h5py.AttributeManager.create = counted(h5py.AttributeManager.create)
h5py.Group.create_group = counted(h5py.Group.create_group)
h5py.Group.__delitem__ = counted(h5py.Group.__delitem__)
add_cycle_scatter(path)
print(writes)
"""


def _sha256(path: Path) -> str:
    return hashlib.sha256(path.read_bytes()).hexdigest()


def _edit_killed_at(record: Path, kill_at: int) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", _KILL_AT_WRITE, str(record), str(kill_at)],
                          capture_output=True, text=True, timeout=300)


def _a_record(folder: Path) -> Path:
    record = folder / SHIPPED.name
    shutil.copyfile(SHIPPED, record)
    return record


def _kill_points(tmp_path: Path) -> int:
    """How many attribute and group writes the edit makes."""
    probe = tmp_path / "probe"
    probe.mkdir()
    done = _edit_killed_at(_a_record(probe), 0)
    assert done.returncode == 0, done.stderr
    return int(done.stdout.split()[-1])


def _check_killed_edit(record: Path, kill_at: int) -> None:
    before = _sha256(record)
    done = _edit_killed_at(record, kill_at)
    assert done.returncode == -signal.SIGKILL, (kill_at, done.stderr)
    assert _sha256(record) == before, f"killed at write {kill_at}: the record changed"
    read_record(record)  # still whole
    assert stale_temporaries(record.parent, ".h5"), "the killed edit's copy is left to clear"


def test_an_edit_killed_midway_leaves_the_record_as_it_was(tmp_path):
    record = _a_record(tmp_path)
    n_writes = _kill_points(tmp_path)
    assert n_writes >= 3
    _check_killed_edit(record, n_writes // 2)
    scatter = add_cycle_scatter(record)  # and the edit, run whole, is there
    assert read_cycle_scatter(record) == scatter


@pytest.mark.slow
def test_an_edit_killed_at_every_one_of_its_writes_leaves_the_record_as_it_was(tmp_path):
    record = _a_record(tmp_path)
    n_writes = _kill_points(tmp_path)
    for kill_at in range(1, n_writes + 1):
        _check_killed_edit(record, kill_at)


def test_a_campaign_clears_a_dead_writer_s_temporary_and_keeps_a_live_one_s(tmp_path):
    """A second `campaign run` on the folder removes what a killed writer left, never the
    record another process is writing at that moment."""
    out = tmp_path / "camp"
    out.mkdir()
    case = CfdCase(1.0, 0.05, 90.0, 30.0, duration=1.0, ramp_time=0.25)
    shutil.copyfile(SHIPPED, out / f"{case.case_id}.h5")
    live = temporary_beside(out / "other_case.h5")  # this process: at work
    gone = subprocess.Popen([sys.executable, "-c", "pass"])
    gone.wait()
    dead = out / f".third_case.h5.abc12345.{gone.pid}.tmp"
    dead.write_bytes(b"\x89HDF")
    run_campaign([case], out, CampaignSetup(), progress=False)
    assert live.exists() and not dead.exists()


def test_results_whose_new_content_was_removed_meanwhile_are_an_error(tmp_path):
    target = tmp_path / "results.h5"
    rf = ResultsFile(target, "w", kind="evaluation")
    rf.h5.attrs["x"] = 1.0
    written = next(p for p in tmp_path.iterdir() if p.name.endswith(f".{os.getpid()}.tmp"))
    rf.h5.close()
    written.unlink()  # as a careless clean-up by another process would
    with pytest.raises(MfflapError, match="was removed before it could take"):
        rf.close()
    assert not target.exists()


def test_the_temporary_name_cannot_be_guessed_and_is_created_exclusively(tmp_path):
    target = tmp_path / "results.h5"
    first, second = temporary_beside(target), temporary_beside(target)
    assert first != second and first.exists() and second.exists()
    assert first.name.endswith(f".{os.getpid()}.tmp")


def _flip_a_byte(path: Path, at: int) -> None:
    data = bytearray(path.read_bytes())
    data[at] ^= 0x10
    path.write_bytes(bytes(data))


def test_a_flipped_bit_anywhere_in_a_written_record_is_a_clean_error_naming_it(tmp_path):
    """Every byte of what a record holds (attributes, scalars, Fletcher-32-guarded arrays,
    compressed or not) is checked when it is read: a flip is an UnreadableRecordError
    naming the file, or the file does not open as HDF5 at all, never a wrong record."""
    from mfflap.errors import UnreadableRecordError
    from mfflap.records.record import write_record

    original = read_record(SHIPPED)
    written = write_record(tmp_path / "whole.h5", original)
    whole = written.read_bytes()
    reference = read_record(written)
    wrong_records = []
    for at in range(0, len(whole), max(len(whole) // 400, 1)):
        flipped = tmp_path / "flipped.h5"
        flipped.write_bytes(whole)
        _flip_a_byte(flipped, at)
        try:
            back = read_record(flipped)
        except UnreadableRecordError as err:
            assert str(flipped) in str(err)
            continue
        except MfflapError as err:  # not an HDF5 file any more, or its structure broken
            assert str(flipped) in str(err)
            continue
        same = (back.loads.normal_force.tobytes() == reference.loads.normal_force.tobytes()
                and back.parameters == reference.parameters
                and back.provenance == reference.provenance
                and back.time.tobytes() == reference.time.tobytes())
        if not same:
            wrong_records.append(at)
    assert not wrong_records, f"flips read back as a wrong record at bytes {wrong_records}"


def test_a_record_that_fails_its_checksum_counts_as_not_done(tmp_path):
    import h5py

    from mfflap.campaign.execute import read_finished_record
    from mfflap.records.record import write_record
    from mfflap.results import CHECKSUM_ATTR

    path = write_record(tmp_path / "rec.h5", read_record(SHIPPED))
    with h5py.File(path, "r+") as h5:  # an edit outside mfflap
        h5["parameters"].attrs["frequency"] = 2.0
        assert CHECKSUM_ATTR in h5.attrs
    record, why = read_finished_record(path)
    assert record is None and "does not match its checksum" in why
