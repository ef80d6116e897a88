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
