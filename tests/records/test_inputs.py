"""CFD records are read only for the plate, fluid and stream they were run for.

Before, a case file with another chord, span or stream velocity identified its Morison
coefficients from the shipped fixtures (run for the paper's plate at 0.3 m/s) without a
word, and a back-test compared such a fixture with the other plate's model.
"""

from __future__ import annotations

import shutil
from dataclasses import replace
from pathlib import Path

import pytest
from click.testing import CliRunner

from mfflap.cli.main import cli
from mfflap.errors import ConfigError
from mfflap.parameters import Fluid, FreeStream, Plate
from mfflap.records.inputs import check_records_inputs, input_mismatches, run_for
from mfflap.records.record import fixture_dir, read_record, write_record

CASE_TEXT = (Path(__file__).parents[2] / "cases" / "paper2026.toml").read_text()
TABLE1 = fixture_dir("table1_coarse")


def _case_file(tmp_path: Path, old: str, new: str) -> Path:
    assert old in CASE_TEXT
    path = tmp_path / "case.toml"
    path.write_text(CASE_TEXT.replace(old, new))
    return path


def test_a_record_says_what_it_was_run_for_from_its_provenance_and_its_folder():
    record = read_record(next(iter(sorted(TABLE1.glob("f*.h5")))))
    # the shipped provenance, and the pivot every run that does not say pitched about
    assert set(run_for(record)) == {"plate.chord", "plate.span", "plate.pivot_chord_fraction"}
    assert run_for(record)["plate.pivot_chord_fraction"][0] == 0.0
    from mfflap.records.inputs import folder_setup

    found = run_for(record, folder_setup(TABLE1))
    assert found["flow.velocity"] == (0.3, "the folder's campaign.toml")
    assert found["fluid.kinematic_viscosity"] == (1e-6, "the folder's campaign.toml")
    assert found["plate.chord"] == (0.16, "its provenance chord_m")  # the record first
    assert input_mismatches(record, Plate(), Fluid(), FreeStream(), folder_setup(TABLE1)) == []
    close = Plate(chord=0.16 * (1 + 1e-9))  # a float's round-off is the same plate
    assert input_mismatches(record, close, Fluid(), FreeStream()) == []
    (m,) = input_mismatches(record, Plate(chord=0.1), Fluid(), FreeStream())
    assert (m.key, m.record_value, m.case_value) == ("plate.chord", 0.16, 0.1)
    # a quarter-chord model is not identified from leading-edge runs unseen
    (m,) = input_mismatches(record, Plate(pivot_chord_fraction=0.25), Fluid(), FreeStream())
    assert (m.key, m.record_value, m.case_value) == ("plate.pivot_chord_fraction", 0.0, 0.25)


def test_the_refusal_counts_the_records_of_each_folder_and_names_the_first_key():
    records = [(read_record(p), TABLE1) for p in sorted(TABLE1.glob("f*.h5"))[:3]]
    with pytest.raises(ConfigError) as err:
        check_records_inputs(records, Plate(), Fluid(), FreeStream(velocity=0.5),
                             case_source="my.toml", use="identification")
    assert err.value.key == "flow.velocity" and err.value.source == "my.toml"
    assert (f"3 records in {TABLE1} ran for flow.velocity = 0.3 (the folder's "
            "campaign.toml), the case file has 0.5") in str(err.value)
    check_records_inputs(records, Plate(), Fluid(), FreeStream(), case_source=None,
                         use="identification")  # the records' own: no refusal


@pytest.mark.parametrize(("old", "new", "said"), [
    ("chord = 0.16 ", "chord = 0.10 ",
     "ran for plate.chord = 0.16 (its provenance chord_m), the case file has 0.1"),
    ("velocity = 0.3 ", "velocity = 0.5 ",
     "ran for flow.velocity = 0.3 (the folder's campaign.toml), the case file has 0.5"),
    ("kinematic_viscosity = 1.0e-6", "kinematic_viscosity = 1.0e-5",
     "ran for fluid.kinematic_viscosity = 1e-06 (the folder's campaign.toml), the case file "
     "has 1e-05"),
])
def test_identify_refuses_records_of_another_plate_fluid_or_stream(tmp_path, old, new, said):
    case = _case_file(tmp_path, old, new)
    out = tmp_path / "out" / "id.h5"
    res = CliRunner().invoke(cli, ["identify", str(case), "--fixtures", str(TABLE1),
                                   "--bootstrap", "0", "--output", str(out)])
    assert res.exit_code == 2, res.output
    text = " ".join(res.output.split())
    assert f"records in {TABLE1} {said}" in text
    assert "would be read as this case's in the identification" in text
    assert not out.parent.exists()


def test_gap_diagnose_refuses_them_too(tmp_path):
    case = _case_file(tmp_path, "chord = 0.16 ", "chord = 0.12 ")
    res = CliRunner().invoke(cli, ["gap", "diagnose", str(case), "--output",
                                   str(tmp_path / "g.h5")])
    assert res.exit_code == 2, res.output
    assert "in the gap diagnosis" in res.output and "the case file has 0.12" in res.output
    assert not (tmp_path / "g.h5").exists()


def test_a_record_that_does_not_say_is_not_refused(tmp_path):
    """A record without the key in its provenance, away from its campaign.toml, cannot be
    checked for the stream: it is read (only what is known is refused)."""
    source = sorted(TABLE1.glob("f*.h5"))[0]
    lone = tmp_path / "records"
    lone.mkdir()
    shutil.copy(source, lone / source.name)
    from mfflap.config import load_case
    from mfflap.identification.workflow import pooled_records

    config = load_case(_case_file(tmp_path, "velocity = 0.3 ", "velocity = 0.5 "))
    records, _ = pooled_records([lone], config)
    assert [r.name for r in records] == [source.stem]
    with pytest.raises(ConfigError, match=r"plate\.chord = 0\.16"):  # the chord it does say
        pooled_records([lone], replace(config, plate=Plate(chord=0.2)))
    record = read_record(source)  # one that says its stream, as records now do
    record.provenance["flow_velocity_m_per_s"] = 0.3
    write_record(lone / source.name, record)
    with pytest.raises(ConfigError, match=r"ran for flow.velocity = 0.3 \(its provenance "
                                          r"flow_velocity_m_per_s\)"):
        pooled_records([lone], config)


def test_a_back_test_fixture_of_the_same_motion_but_another_plate_is_not_used(
        tmp_path, optimisation_file):
    """The optimised motions match the shipped back-test fixtures; with the span doubled in
    the optimisation's case they are not this case's CFD: not back-tested, exit status 1."""
    import h5py

    doubled = tmp_path / "opt.h5"
    shutil.copy(optimisation_file, doubled)
    from mfflap.results import seal

    with h5py.File(doubled, "r+") as h5:  # an edit that keeps the file's checksum true
        h5["inputs"].attrs["config_toml"] = h5["inputs"].attrs["config_toml"].replace(
            "span = 0.18", "span = 0.36")
        seal(h5)
    res = CliRunner().invoke(cli, ["backtest", str(doubled)])
    assert res.exit_code == 1, res.output
    assert res.stdout.count("NOT BACK-TESTED: fixture backtest_") == 2
    assert ("matches the motion but ran for plate.span = 0.18 (its provenance span_m), the "
            "case has 0.36") in res.stdout


def test_a_records_parameters_are_read_without_its_histories(tmp_path):
    from mfflap.errors import MfflapError
    from mfflap.records.record import read_record_parameters

    for path in sorted(fixture_dir("backtest_filtered").glob("backtest_*.h5"))[:3]:
        assert read_record_parameters(path) == read_record(path).parameters
        assert read_record_parameters(path)["period"] > 0
    other = tmp_path / "other.h5"
    other.write_bytes(b"not an HDF5 file")
    with pytest.raises(MfflapError, match=r"other\.h5"):
        read_record_parameters(other)
