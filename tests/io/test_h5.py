"""HDF5 records (gaitcli/io/h5.py): any stage result round-trips to the same object; units from field names."""

from __future__ import annotations

from dataclasses import dataclass, field

import h5py
import numpy as np
import pytest

from gaitcli.core.container import FootLoad, Trial
from gaitcli.core.events import Events
from gaitcli.core.recording import Markers
from gaitcli.io.h5 import read_records, read_result, record_datasets, unit_of, write_h5


@dataclass(frozen=True)
class Leaf:
    force_N: np.ndarray
    label: str = ""


@dataclass(frozen=True)
class Record:
    time_s: np.ndarray
    angle_rad: np.ndarray
    count: int
    ratio: float
    flag: bool
    names: tuple[str, ...]
    frames: tuple[int, ...]
    leaves: dict[str, Leaf]
    items: list[Leaf]
    optional: Leaf | None = None
    note: str = "default"
    extra: dict = field(default_factory=dict)


@dataclass(frozen=True)
class Kind(Leaf):
    """A kind of Leaf: a field typed Leaf may hold one."""

    stiffness_Nm_per_rad: float = 0.0


@dataclass(frozen=True)
class Holder:
    leaf: Leaf | None = None


def test_a_field_typed_by_a_base_class_reads_back_the_kind_it_held(tmp_path):
    path = tmp_path / "k.h5"
    write_h5(path, record_datasets("result", Holder(Kind(np.ones(2), "spring", -300.0))), {})
    back = read_result(path, Holder).leaf
    assert type(back) is Kind and back.stiffness_Nm_per_rad == -300.0 and back.label == "spring"
    write_h5(path, record_datasets("result", Holder(Leaf(np.ones(2), "plain"))), {})
    assert type(read_result(path, Holder).leaf) is Leaf


@pytest.mark.parametrize("name,unit", [("force_N", "N"), ("cop_m", "m"), ("free_moment_Nm", "N*m"),
                                       ("speed_m_s", "m/s"), ("cost_of_transport_J_per_m", "J/m"),
                                       ("inertia_kgm2", "kg*m^2"), ("time_s", "s"), ("activations", "1")])
def test_units_come_from_the_field_names(name, unit):
    assert unit_of(name) == unit


def test_a_nested_record_round_trips_exactly(tmp_path):
    rng = np.random.default_rng(0)
    record = Record(time_s=np.arange(5) / 100, angle_rad=rng.normal(size=(5, 3)), count=3, ratio=0.25, flag=True,
                    names=("iliopsoas", "vasti"), frames=(2, 7), leaves={"r": Leaf(rng.normal(size=(5, 3)), "right"),
                                                                         "l": Leaf(np.zeros((5, 3)))},
                    items=[Leaf(np.ones(2)), Leaf(np.full(2, 2.0), "second")], note="ünïcode",
                    extra={"a": [1.0, 2.0], "b": "text"})
    path = tmp_path / "r.h5"
    write_h5(path, record_datasets("result", record), {"k": "v"})
    back = read_result(path, Record)
    assert back.names == record.names and back.frames == (2, 7) and back.note == "ünïcode" and back.optional is None
    assert (back.count, back.ratio, back.flag) == (3, 0.25, True) and isinstance(back.count, int)
    np.testing.assert_array_equal(back.angle_rad, record.angle_rad)
    assert list(back.leaves) == ["r", "l"] and back.leaves["r"].label == "right"
    np.testing.assert_array_equal(back.leaves["r"].force_N, record.leaves["r"].force_N)
    assert [leaf.label for leaf in back.items] == ["", "second"]
    assert back.extra["b"] == "text"
    with h5py.File(path, "r") as h5:
        assert [leaf.label for leaf in read_records(h5["result/items"], Leaf)] == ["", "second"]
    np.testing.assert_array_equal(back.extra["a"], [1.0, 2.0])
    with h5py.File(path, "r") as h5:
        assert h5["result/leaves/r/force_N"].attrs["units"] == "N"
        assert h5["result/time_s"].attrs["units"] == "s" and h5["result/angle_rad"].attrs["units"] == "rad"


def test_the_trial_container_round_trips(tmp_path):
    n = 4
    markers = Markers(("CAr", "FMr"), np.arange(n * 2 * 3, dtype=float).reshape(n, 2, 3) / 10, 100.0, first_frame=7)
    feet = {"r": FootLoad(np.ones((n, 3)), np.zeros((n, 3)), np.zeros(n), np.array([True, False, True, True])),
            "l": FootLoad.unmeasured(n, np.ones(n, bool))}
    events = Events([1, 2], [0.01, 0.02], ["r", "l"], ["heel_strike", "toe_off"], ["plate", "kinematics"])
    trial = Trial(markers, feet, events, history=("read x", "filtered"), source="x.c3d", lab_to_model=np.eye(3))
    path = tmp_path / "t.h5"
    write_h5(path, record_datasets("trial", trial), {})
    back = read_result(path, Trial, "trial")
    assert back.markers.labels == ("CAr", "FMr") and back.markers.first_frame == 7 and back.history == trial.history
    np.testing.assert_array_equal(back.markers.positions_m, markers.positions_m)
    assert back.feet["l"].on_plates is False and back.feet["r"].on_plates is True
    np.testing.assert_array_equal(back.load_known("r"), [True, False, True, True])
    np.testing.assert_array_equal(back.all_loads_known, [True, False, True, True])
    assert list(back.events.side) == ["r", "l"] and list(back.events.source) == ["plate", "kinematics"]


def test_a_group_where_a_dataset_belongs_is_an_input_error(tmp_path):
    """A damaged or foreign file holding a group under a dataset's name: an InputError naming it, no crash."""
    from gaitcli.errors import InputError
    from gaitcli.io.h5 import checked

    path = tmp_path / "foreign.h5"
    with h5py.File(path, "w") as h5:
        h5.create_group("result/design")
    with h5py.File(path, "r") as h5, pytest.raises(InputError, match="result/design.*a group"):
        checked(h5["result/design"])


def test_one_field_is_read_typed_and_a_group_in_its_place_is_an_input_error(tmp_path):
    from gaitcli.errors import InputError
    from gaitcli.io.h5 import read_field

    path = tmp_path / "r.h5"
    write_h5(path, record_datasets("result", Leaf(np.array([[1.0, 2.0, 3.0]]), "right")), {})
    np.testing.assert_array_equal(read_field(path, Leaf, "force_N"), [[1.0, 2.0, 3.0]])
    assert read_field(path, Leaf, "label") == "right"
    foreign = tmp_path / "foreign.h5"
    with h5py.File(foreign, "w") as h5:
        h5.create_group("result/force_N")
    with pytest.raises(InputError, match="result/force_N.*a group"):
        read_field(foreign, Leaf, "force_N")
    with pytest.raises(InputError, match="not an HDF5 file of gait x"):  # the field is missing
        read_field(foreign, Leaf, "label", what="gait x")


def test_a_list_of_records_and_the_root_attributes_are_read_from_the_path(tmp_path):
    from gaitcli.io.h5 import file_attrs

    path = tmp_path / "r.h5"
    write_h5(path, record_datasets("items", [Leaf(np.ones(2), "a"), Leaf(np.zeros(2), "b")]),
             {"trial": "walk 1", "stage_key": "{}"})
    assert [leaf.label for leaf in read_result(path, list[Leaf], "items")] == ["a", "b"]
    assert file_attrs(path) == {"trial": "walk 1", "stage_key": "{}"}


@pytest.mark.parametrize("content", [b"", b"\x89HDF\r\n\x1a\n" + bytes(100), b"time_s,x\n0,1\n"])
def test_a_damaged_file_read_back_is_an_input_error_naming_it(tmp_path, content):
    from gaitcli.errors import InputError
    from gaitcli.io.h5 import file_attrs

    path = tmp_path / "idyn.h5"
    path.write_bytes(content)
    for read in (lambda: read_result(path, Leaf), lambda: file_attrs(path)):
        with pytest.raises(InputError, match="idyn.h5"):
            read()


def test_a_table_is_read_with_its_column_names_units_and_convention(tmp_path):
    from gaitcli.io.h5 import Dataset, column_table

    values = np.arange(6.0).reshape(3, 2)
    path = tmp_path / "t.h5"
    write_h5(path, {"angles": Dataset(values, "deg", {"columns": "hip_r_flexion,knee_r_flexion",
                                                      "convention": "flexion positive"}),
                    "powers": Dataset(values, "W", {"joints": "hip_r,knee_r"})}, {})
    with h5py.File(path, "r") as h5:
        angles, powers = column_table(h5["angles"]), column_table(h5["powers"], "joints")
    assert angles.columns == ("hip_r_flexion", "knee_r_flexion") and angles.units == "deg"
    assert angles.convention == "flexion positive" and powers.columns == ("hip_r", "knee_r") and powers.units == "W"
    np.testing.assert_array_equal(angles.column("knee_r_flexion"), [1.0, 3.0, 5.0])
