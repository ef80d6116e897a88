"""Damaged C3D files (issue 9): seeded single-byte mutations of the header and the parameter section of a
sample trial and of c3d.org's Eb015pi.c3d (integer storage, another writer), each read by ``read_c3d``. Every
read must end in a recording or a one-line InputError, within its time limit: no crash (once a segfault of the
C3D library killed gait), no hang, no runaway allocation (once 12.7 GB for a 0.5 MB file), no other exception.

The mutations of the sample trial go to its first :data:`SHORT_FRAMES` frames, as the sample's writer
(``io/c3d_write``) writes them: the same header and parameter section but for the frame counts, whose damage is
the test's, and a tenth of the data to convert on every read (the sample's 428 frames and 4 280 plate samples
took 150 ms of a read's 160). Those of Eb015pi.c3d go to its first SHORT_FRAMES frames too, cut from its bytes
(:func:`_cut_bytes`): its own header and parameter section, integer data and all, but for the two frame counts
(its 450 frames took half of each mutated read's 50 ms of processor time)."""

from __future__ import annotations

import warnings
from pathlib import Path

import numpy as np
import pytest

from gaitcli.core.recording import Recording
from gaitcli.errors import InputError
from gaitcli.io.c3d import read_c3d
from gaitcli.resources import sample_trial

from ..conftest import SHARED_C3D

MUTATIONS = {"sample": 60, "lab": 140}  # 200 in all; the lab file's part skips without ../shared
SHORT_FRAMES = 40  # marker frames of the sample trial's mutated copies (400 plate samples)
CHUNKS = 4  # tests per file, so that pytest-xdist shares the reads out
LIMIT_S = 10.0


def _mutations(source: Path, seed: int, count: int) -> list[tuple[int, int]]:
    """(byte offset, new value) pairs inside the header and the parameter section, seeded."""
    data = source.read_bytes()
    end = (data[0] - 1) * 512 + 512 * data[(data[0] - 1) * 512 + 2]
    rng = np.random.default_rng(seed)
    offsets = rng.integers(0, min(end, len(data)), count)
    values = [(int(data[o]) + int(rng.integers(1, 256))) % 256 for o in offsets]
    return list(zip(map(int, offsets), values))


def _read_mutated(source: Path, tmp_path: Path, seed: int, count: int, chunk: int, monkeypatch) -> dict:
    import gaitcli.io.c3d as c3d_module

    data = bytearray(source.read_bytes())
    # the bounds exactly: 10 s and 1 GB per read (the reader's limits grow with the file's size)
    monkeypatch.setattr(c3d_module, "READ_TIME_S", LIMIT_S - len(data) / 1e6)
    monkeypatch.setattr(c3d_module, "READ_MEMORY_BYTES", (1 << 30) - c3d_module.READ_BYTES_PER_BYTE * len(data))
    outcomes = {"read": 0, "refused": 0}
    for offset, value in _mutations(source, seed, count)[chunk::CHUNKS]:
        mutated = bytearray(data)
        mutated[offset] = value
        path = tmp_path / f"mutated_{offset}_{value}.c3d"
        path.write_bytes(bytes(mutated))
        try:
            with warnings.catch_warnings():
                warnings.simplefilter("ignore")
                recording = read_c3d(path)
            assert isinstance(recording, Recording)
            outcomes["read"] += 1
        except InputError as exc:
            message = str(exc)
            assert "\n" not in message and len(message) < 400 and str(path) in message, message
            assert "ignoreBadFormatting" not in message, message  # the library's advice, not gait's
            outcomes["refused"] += 1
        path.unlink()
    return outcomes


@pytest.fixture(scope="module")
def short_sample(tmp_path_factory) -> Path:
    """The normal sample trial's first SHORT_FRAMES frames and their plate samples, written as the sample was."""
    from gaitcli.core.recording import ForcePlate, Markers
    from gaitcli.io.c3d_write import write_c3d

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = read_c3d(sample_trial("normal") / "trial.c3d")
    m = whole.markers
    per_frame = [round(p.rate_hz / m.rate_hz) for p in whole.plates]
    plates = [ForcePlate(p.name, p.force_N[:SHORT_FRAMES * k], p.moment_Nm[:SHORT_FRAMES * k], p.centre_m,
                         p.corners_m, p.rate_hz, p.plate_type) for p, k in zip(whole.plates, per_frame)]
    path = tmp_path_factory.mktemp("short_sample") / "trial.c3d"
    return write_c3d(path, Markers(m.labels, m.positions_m[:SHORT_FRAMES], m.rate_hz, m.first_frame), plates,
                     model_to_lab=whole.lab_to_model.T)


def _cut_bytes(source: Path, frames: int, target: Path) -> Path:
    """``source``'s first ``frames`` frames, byte for byte: its header and parameter section with the header's last
    frame and POINT:FRAMES set to them, and the data section cut after them (an Intel file's, as Eb015pi.c3d)."""
    import struct

    from gaitcli.io.c3d.header import check_parameters

    data = bytearray(source.read_bytes())
    points, analogs, first = struct.unpack("<3H", data[2:8])
    scale, data_block = struct.unpack("<f", data[12:16])[0], struct.unpack("<H", data[16:18])[0]
    frame_bytes = (4 * points + analogs) * (2 if scale > 0 else 4)  # integer or float storage
    data[8:10] = struct.pack("<H", first + frames - 1)
    record = check_parameters(source, (data[0] - 1) * 512, data[(data[0] - 1) * 512 + 2], len(data))["POINT", "FRAMES"]
    assert record.kind == 2
    data[record.data_offset:record.data_offset + 2] = struct.pack("<H", frames)
    end = (data_block - 1) * 512 + frames * frame_bytes
    target.write_bytes(bytes(data[:end]) + bytes(-end % 512))
    return target


@pytest.fixture(scope="module")
def short_lab(tmp_path_factory) -> Path:
    """Eb015pi.c3d's first SHORT_FRAMES frames (:func:`_cut_bytes`); skipped without ../shared."""
    if not SHARED_C3D.is_dir():
        pytest.skip("../shared/data/c3d is absent")
    return _cut_bytes(SHARED_C3D / "Eb015pi.c3d", SHORT_FRAMES, tmp_path_factory.mktemp("short_lab") / "Eb015pi.c3d")


def test_the_short_lab_file_is_the_lab_files_start(short_lab):
    """What the lab file's mutations damage: its own bytes up to the data but for the frame counts, and its
    markers and plates, cut short (in the lab's axes: the walking direction of 40 frames is another matter)."""
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole = read_c3d(SHARED_C3D / "Eb015pi.c3d", to_model_axes=False)
        short = read_c3d(short_lab, to_model_axes=False)
    assert whole.markers.n_frames == 450 and short.markers.n_frames == SHORT_FRAMES
    assert short.markers.labels == whole.markers.labels and short.markers.rate_hz == whole.markers.rate_hz
    np.testing.assert_array_equal(short.markers.positions_m, whole.markers.positions_m[:SHORT_FRAMES])
    assert len(short.plates) == len(whole.plates) == 2
    for p, q in zip(short.plates, whole.plates):
        assert p.n_samples == 4 * SHORT_FRAMES and p.rate_hz == q.rate_hz
        np.testing.assert_allclose(p.force_N, q.force_N[:p.n_samples], atol=1e-9)
        np.testing.assert_allclose(p.corners_m, q.corners_m)
    whole_bytes, short_bytes = (SHARED_C3D / "Eb015pi.c3d").read_bytes(), short_lab.read_bytes()
    start = (whole_bytes[16] + 256 * whole_bytes[17] - 1) * 512  # the data section's
    differ = [k for k in range(start) if whole_bytes[k] != short_bytes[k]]
    assert differ == [8, 9, 4481, 4482], differ  # the header's last frame and POINT:FRAMES (450 → 40)
    assert short_bytes[8:10] == short_bytes[4481:4483] == SHORT_FRAMES.to_bytes(2, "little")


def test_the_short_sample_is_the_samples_start(short_sample):
    """What the mutations damage: the sample's own parameter layout, and its data, cut short."""
    import ezc3d

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        whole, short = read_c3d(sample_trial("normal") / "trial.c3d"), read_c3d(short_sample)
    np.testing.assert_allclose(short.markers.positions_m, whole.markers.positions_m[:SHORT_FRAMES], atol=1e-6)
    assert [p.n_samples for p in short.plates] == [10 * SHORT_FRAMES] * len(whole.plates)
    for p, q in zip(short.plates, whole.plates):
        np.testing.assert_allclose(p.force_N, q.force_N[:p.n_samples], atol=1e-3)
    a, b = ezc3d.c3d(str(sample_trial("normal") / "trial.c3d")), ezc3d.c3d(str(short_sample))
    assert {g: sorted(a["parameters"][g]) for g in a["parameters"]} == \
        {g: sorted(b["parameters"][g]) for g in b["parameters"]}


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_mutated_sample_trial(tmp_path, chunk, monkeypatch, short_sample):
    outcomes = _read_mutated(short_sample, tmp_path, seed=9, count=MUTATIONS["sample"], chunk=chunk,
                             monkeypatch=monkeypatch)
    assert sum(outcomes.values()) == len(range(chunk, MUTATIONS["sample"], CHUNKS))


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_mutated_lab_file(tmp_path, chunk, monkeypatch, short_lab):
    outcomes = _read_mutated(short_lab, tmp_path, seed=10, count=MUTATIONS["lab"], chunk=chunk,
                             monkeypatch=monkeypatch)
    assert sum(outcomes.values()) == len(range(chunk, MUTATIONS["lab"], CHUNKS))


# --- parameters that change what the data mean (issue 53, item 1) ------------------------------------------
#: (group, name) of the sample's parameters that say how its data are read, and the values a damaged file holds
#: (ANALOG:GEN_SCALE scales every plate's force alike: nothing in the file tells, and the idyn stage's mass check
#: warns of it, test_a_plate_scale_off_is_warned_by_the_mass_check)
MEANING = {("POINT", "RATE"): 4, ("ANALOG", "RATE"): 4, ("POINT", "SCALE"): 4, ("POINT", "FRAMES"): 2,
           ("POINT", "USED"): 2, ("ANALOG", "USED"): 2, ("POINT", "UNITS"): -1}
PARAMETER_MUTATIONS = 28


def _parameter_mutations(source: Path, seed: int, count: int) -> list[tuple[tuple[str, str], bytes]]:
    """(parameter, its new bytes), seeded: a number scaled, negated, zeroed, made odd or NaN; a unit renamed."""
    import struct

    from gaitcli.io.c3d.header import check_parameters

    data = source.read_bytes()
    records = check_parameters(source, (data[0] - 1) * 512, data[(data[0] - 1) * 512 + 2], len(data))
    rng = np.random.default_rng(seed)
    keys = sorted(MEANING)
    out = []
    for _ in range(count):
        key = keys[int(rng.integers(len(keys)))]
        record = records[key]
        raw = data[record.data_offset:record.data_offset + max(2, abs(record.kind))]
        if record.kind == 4:
            value = struct.unpack("<f", raw[:4])[0]
            new = float(rng.choice([0.0, -value, value * 10, value / 10, value + 1, value * 1.37, float("nan")]))
            out.append((key, struct.pack("<f", new)))
        elif record.kind == 2:
            value = struct.unpack("<H", raw[:2])[0]
            new = int(rng.choice([0, value + 1, max(value - 1, 0), value * 2, 65535]))
            out.append((key, struct.pack("<H", new)))
        else:
            out.append((key, str(rng.choice(["m ", "cm", "in", "  ", "MM"])).encode()))
    return out


def _mutated_parameter(source: Path, tmp_path: Path, key, new: bytes) -> Path:
    from gaitcli.io.c3d.header import check_parameters

    data = bytearray(source.read_bytes())
    record = check_parameters(source, (data[0] - 1) * 512, data[(data[0] - 1) * 512 + 2], len(data))[key]
    data[record.data_offset:record.data_offset + len(new)] = new
    path = tmp_path / "mutated.c3d"
    path.write_bytes(bytes(data))
    return path


def _same(a: Recording, b: Recording) -> bool:
    if a.markers.positions_m.shape != b.markers.positions_m.shape or len(a.plates) != len(b.plates):
        return False
    same = np.allclose(a.markers.positions_m, b.markers.positions_m, equal_nan=True, atol=1e-9)
    for p, q in zip(a.plates, b.plates):
        same &= p.rate_hz == q.rate_hz and np.allclose(p.force_N, q.force_N, equal_nan=True, atol=1e-9)
    return bool(same and a.markers.rate_hz == b.markers.rate_hz)


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_a_parameter_that_changes_the_datas_meaning_is_refused_or_warned(tmp_path, chunk, short_sample):
    """Seeded mutations of the parameters that say how the data read (rates, scales, frame and point counts,
    units): each read ends in an InputError naming the file, or in the same markers and plates as the unmutated
    file's, or in a warning that says what was assumed. Before issue 53 an analog rate of 0 read as 0 plates
    and 3022 filled gaps without a word."""
    import warnings as w

    from gaitcli.errors import GaitWarning

    source = short_sample
    with w.catch_warnings():
        w.simplefilter("ignore")
        base = read_c3d(source)
    silent = []
    for key, new in _parameter_mutations(source, seed=53, count=PARAMETER_MUTATIONS)[chunk::CHUNKS]:
        path = _mutated_parameter(source, tmp_path, key, new)
        with w.catch_warnings(record=True) as caught:
            w.simplefilter("always")
            try:
                recording = read_c3d(path)
            except InputError as exc:
                assert str(path) in str(exc) and "\n" not in str(exc), str(exc)
                continue
        warned = [c for c in caught if issubclass(c.category, GaitWarning)]
        if not _same(recording, base) and not warned:
            silent.append((key, new))
    assert not silent, f"read as other data without a warning: {silent}"


# --- the EVENT group damaged (issue 53, item 2) ----------------------------------------------------------
EVENT_MUTATIONS = 16
KINDS = {"heel_strike": "Foot Strike", "toe_off": "Foot Off"}


def _with_events(source: Path, target: Path, rows) -> Path:
    """``source`` with ``rows`` (time s from the first frame, side, kind) as its EVENT group (ezc3d's add_event)."""
    import ezc3d

    c = ezc3d.c3d(str(source))
    start = c["header"]["points"]["first_frame"] / float(c["parameters"]["POINT"]["RATE"]["value"][0])
    for t, side, kind in rows:
        c.add_event([0, float(start + t)], context="Right" if side == "r" else "Left", label=KINDS[kind])
    c.write(str(target))
    return target


def _event_mutations(rows: list, seed: int, count: int) -> list[list]:
    """Seeded damage to the lab's events: one moved by 0.25–0.6 s, its side swapped, its kind swapped, doubled
    0.1 s on, or a run of 5–40 events at random times added."""
    rng = np.random.default_rng(seed)
    out = []
    for _ in range(count):
        damaged = list(rows)
        k = int(rng.integers(len(damaged)))
        t, side, kind = damaged[k]
        how = int(rng.integers(5))
        if how == 0:
            damaged[k] = (max(0.0, t + float(rng.choice([-1, 1]) * rng.uniform(0.25, 0.6))), side, kind)
        elif how == 1:
            damaged[k] = (t, "l" if side == "r" else "r", kind)
        elif how == 2:
            damaged[k] = (t, side, "toe_off" if kind == "heel_strike" else "heel_strike")
        elif how == 3:
            damaged.append((t + 0.1, side, kind))
        else:
            damaged += [(float(rng.uniform(0, 4.2)), str(rng.choice(["r", "l"])), str(rng.choice(list(KINDS))))
                        for _ in range(int(rng.integers(5, 41)))]
        out.append(damaged)
    return out


@pytest.fixture(scope="module")
def true_events(tmp_path_factory):
    """The sample walk's true events (truth/events.csv) as rows, and the events the filter stage takes from the
    sample with those rows as its EVENT group."""
    import pandas as pd

    from gaitcli.signal.stage import FilterConfig, filter_trial

    truth = pd.read_csv(sample_trial("normal") / "truth" / "events.csv")
    rows = [(float(t), str(s), str(k)) for t, s, k in zip(truth.time_s, truth.side, truth.event)]
    path = _with_events(sample_trial("normal") / "trial.c3d", tmp_path_factory.mktemp("events") / "base.c3d", rows)
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        return rows, filter_trial(read_c3d(path), FilterConfig()).trial.events


@pytest.mark.parametrize("chunk", range(CHUNKS))
def test_damaged_events_are_refused_or_set_aside_with_a_warning(tmp_path, chunk, true_events):
    """The sample walk with its true events as the lab's EVENT group, then seeded damage (above): the filter
    stage either refuses the file (one line) or uses the true events, or warns of the strides it set aside. A
    damaged EVENT group never walks silently into the strides."""
    import warnings as w

    from gaitcli.errors import GaitWarning
    from gaitcli.signal.stage import FilterConfig, filter_trial

    source = sample_trial("normal") / "trial.c3d"
    rows, base = true_events
    silent = []
    for damaged in _event_mutations(rows, seed=54, count=EVENT_MUTATIONS)[chunk::CHUNKS]:
        path = _with_events(source, tmp_path / "damaged.c3d", damaged)
        with w.catch_warnings(record=True) as caught:
            w.simplefilter("always")
            try:
                events = filter_trial(read_c3d(path), FilterConfig(), path=path).trial.events
            except InputError as exc:
                assert str(path) in str(exc) and "\n" not in str(exc), str(exc)
                continue
        same = len(events) == len(base) and np.allclose(events.time_s, base.time_s, atol=1e-3) and \
            list(events.side) == list(base.side) and list(events.kind) == list(base.kind)
        if not same and not any(issubclass(c.category, GaitWarning) for c in caught):
            silent.append(sorted(set(damaged) - set(rows)))
    assert not silent, f"damaged events used without a warning: {silent}"
