"""Parameters that disagree with the header that lays out the data section (issue 53, item 1): POINT:RATE,
ANALOG:RATE and POINT:SCALE changed in the bytes of the bundled sample's C3D. Before, `gait filter` read such a
file with exit 0 (an analog rate of 0: no plates and 3022 gaps filled); now each is exit 2 naming the parameter,
its value and what the header says, before the C3D library reads anything."""

from __future__ import annotations

import shutil
import struct
from pathlib import Path

import pytest

from gaitcli.errors import InputError
from gaitcli.io.c3d.header import check_file, check_parameters
from gaitcli.resources import sample_trial

SAMPLE = sample_trial("normal") / "trial.c3d"


def patched(tmp_path: Path, group: str, name: str, value: float) -> Path:
    """A copy of the sample with the float parameter GROUP:NAME set to ``value`` in its bytes (Intel)."""
    path = tmp_path / "trial.c3d"
    shutil.copy(SAMPLE, path)
    data = bytearray(path.read_bytes())
    offset, blocks = (data[0] - 1) * 512, data[(data[0] - 1) * 512 + 2]
    record = check_parameters(path, offset, blocks, len(data))[(group, name)]
    assert record.kind == 4
    data[record.data_offset:record.data_offset + 4] = struct.pack("<f", value)
    path.write_bytes(data)
    return path


def test_the_sample_as_shipped_passes():
    assert check_file(SAMPLE) == 428


@pytest.mark.parametrize("group, name, value, expected", [
    ("POINT", "RATE", 0.0, "POINT:RATE: got 0 (expected the header's 100 Hz"),
    ("POINT", "RATE", 37.0, "POINT:RATE: got 37 (expected the header's 100 Hz"),
    ("ANALOG", "RATE", 0.0, "ANALOG:RATE: got 0 (expected 1000 Hz: the header's 10 samples per frame at 100 Hz"),
    ("ANALOG", "RATE", 1001.0, "ANALOG:RATE: got 1001 (expected 1000 Hz"),
    ("POINT", "SCALE", 0.1, "POINT:SCALE: got 0.1 (expected a negative scale: the header stores the data as "
                            "floats"),
])
def test_a_parameter_against_its_header_is_exit_2_naming_it(tmp_path, group, name, value, expected):
    path = patched(tmp_path, group, name, value)
    with pytest.raises(InputError) as info:
        check_file(path)
    assert info.value.field == f"{group}:{name}" and expected in str(info.value)


def test_a_float_files_scale_of_another_size_reads_the_same_markers(tmp_path):
    """A float file's POINT:SCALE only says "floats" by its sign (the C3D library does not use its size, and
    writes −1 in the header whatever the parameter holds): −0.01 against the header's −1 passes."""
    check_file(patched(tmp_path, "POINT", "SCALE", -0.01))


def test_real_files_of_many_labs_pass(shared_c3d_dir, shared_pig_dir):
    for path in [*shared_c3d_dir.glob("*.c3d"), *shared_pig_dir.glob("*.c3d")]:
        if path.name == "sgi_int.c3d":  # refused for its processor, before any parameter
            continue
        check_file(path)
