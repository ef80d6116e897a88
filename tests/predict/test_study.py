"""Prediction studies and starts (gaitcli/run/studies.py, gaitcli/predict/starts.py): the bundled study files'
grids, seeded perturbed starts, and the optimal prosthesis never reporting a higher J than the commercial foot it
started from."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.predict import starts
from gaitcli.predict.layout import DesignLayout, box_bounds
from gaitcli.predict.prosthesis import COMMERCIAL_FEET
from gaitcli.predict.reference import read_reference
from gaitcli.predict.stage import PredictConfig
from gaitcli.resources import bundled_reference, study_file
from gaitcli.run import studies
from gaitcli.run.cluster import workers


def spec_of(name: str) -> studies.StudySpec:
    return studies.read_study(study_file(name))


def test_the_prosthesis_study_is_table_5_3s_grid():
    chains = studies.study_cases(spec_of("prostheses"))
    assert len(chains) == 2  # one per speed, 1.00 and 1.33 m/s
    for chain in chains:
        previous = previous_sach = None
        assert len({c.speed_m_s for c in chain}) == 1 and len(chain) == 4 * 5
        for k in range(0, 20, 5):  # per weight set a)–d)
            group = chain[k:k + 5]
            normal, optimal = group[0], group[-1]
            assert [c.condition for c in group] == ["normal", "sach", "seattle", "flex", "optimal"]
            assert len({c.cfg.weights for c in group}) == 1
            assert all(c.cfg.strength() == 1.5 for c in group)  # F_max +50 %, the normal comparison run too
            assert all(c.cfg.time_limit_s == 150 for c in group)
            assert normal.starts_from == (() if k == 0 else (previous,))
            sach = group[1].name
            first_foot = (normal.name,) if k == 0 else (previous_sach, normal.name)  # a foot from the last foot
            assert [c.starts_from for c in group[1:4]] == [first_foot, (sach, normal.name), (sach, normal.name)]
            assert optimal.starts_from == tuple(c.name for c in group[1:4]) + (normal.name,)
            previous, previous_sach = normal.name, sach
    assert {c.weight_set for chain in chains for c in chain} == {"a", "b", "c", "d"}
    assert len({c.name for chain in chains for c in chain}) == 40  # one folder per case


def test_the_foot_mass_study_is_table_5_2s_grid():
    (chain,) = studies.study_cases(spec_of("foot_mass"))
    assert len(chain) == 8
    for k in range(0, 8, 2):
        normal, heavy = chain[k:k + 2]
        assert (normal.cfg.foot_mass_kg, heavy.cfg.foot_mass_kg) == (0.0, 2.0)
        assert normal.cfg.strength() == heavy.cfg.strength() == 1.0 and normal.speed_m_s == 1.1275
        # +2 kg from the last weight set's +2 kg solution where it converged, else from its own normal one
        assert heavy.starts_from == ((normal.name,) if k == 0 else (chain[k - 1].name, normal.name))


@pytest.mark.parametrize("change, field", [({"conditions": ["normal", "optimal"]}, "conditions"),
                                           ({"weights": ["3,3"]}, "weights"), ({"starts": 0}, "starts"),
                                           ({"speeds": [1.0]}, "speeds"), ({"time_limit_s": -1}, "time_limit_s")])
def test_a_bad_study_file_is_refused_naming_the_field(change, field):
    data = {"speeds_m_s": [1.0], "weights": ["b"], "conditions": ["normal"], **change}
    with pytest.raises(InputError) as caught:
        studies.StudySpec.from_mapping(data, "study.yaml")
    assert caught.value.field == field


def test_perturbed_starts_are_seeded_inside_the_bounds_and_keep_the_speed():
    cfg = PredictConfig(speed_m_s=1.2)
    reference = read_reference(bundled_reference())
    a, b, c = (starts.perturbed_guess(cfg, None, reference, seed) for seed in (3, 3, 4))
    np.testing.assert_array_equal(a, b)
    assert np.abs(a - c).max() > 0.01
    layout = DesignLayout.build(cfg.nodes, symmetric=True)
    low, high = box_bounds(layout)
    assert np.all(a >= low) and np.all(a <= high)
    period = layout.phase_durations(a).sum()
    assert period == pytest.approx(sum(layout.step_lengths(a)) / 1.2, rel=1e-12)


@dataclass(frozen=True)
class Solved:
    """What predict_optimal reads of a result."""

    objective: float
    converged: bool
    prosthesis: object = None
    design: np.ndarray = dataclasses.field(default_factory=lambda: np.zeros(3))
    history: tuple = ()


@pytest.mark.parametrize("optimal_objectives, expected", [((5.0, 6.0), 5.0), ((9.0, 8.5), 7.0)])
def test_the_optimal_prosthesis_never_ends_above_the_foot_it_started_from(monkeypatch, optimal_objectives, expected):
    # Seattle (J 7.0) is the best foot; the optimal runs from it and from the normal gait end at the given Js:
    # the result is the best of them and of Seattle's solution, which is a point of the optimal problem
    feet = {"sach": Solved(8.0, True, COMMERCIAL_FEET["sach"]),
            "seattle": Solved(7.0, True, COMMERCIAL_FEET["seattle"]),
            "flex": Solved(9.0, True, COMMERCIAL_FEET["flex"])}
    runs = iter(optimal_objectives)
    started = []

    def fake_run(cfg, *, params, reference, init, report=None, device=None, cache=None):
        started.append((cfg.prosthesis, device.coefficients().tolist()))
        return Solved(next(runs), True, device)

    monkeypatch.setattr(starts, "run_predict", fake_run)
    result = starts.predict_optimal(PredictConfig(prosthesis="optimal"), params=None, reference=None, feet=feet,
                                   normal=Solved(4.0, True))
    assert result.objective == expected
    # from the normal solution too only when the start from Seattle's did not improve on it
    assert started == [("optimal", COMMERCIAL_FEET["seattle"].coefficients().tolist())] * (1 if expected < 7 else 2)
    if expected == 7.0:
        assert result.prosthesis.name == "optimal (= Seattle)"
        np.testing.assert_array_equal(result.prosthesis.coefficients(), COMMERCIAL_FEET["seattle"].coefficients())


def test_starts_run_the_guess_and_seeded_perturbations_and_count_the_agreeing(monkeypatch):
    # --starts 4 (one worker: this process): start 0 from the given χ, starts 1–3 from perturbed_guess(seed + k);
    # the best converged J is kept and the starts within 1 % of it are counted
    reference = read_reference(bundled_reference())
    cfg = PredictConfig(starts=4, seed=7)
    given = np.full(219, 0.5)
    objectives = {0: 10.0, 1: 10.05, 2: 9.0, 3: 8.0}
    converged = {0: True, 1: True, 2: True, 3: False}
    seen = []

    def fake_run(cfg, *, params, reference, init, device=None, report=None, cache=None):
        k = next(k for k in range(4) if np.array_equal(init, given if k == 0 else
                                                         starts.perturbed_guess(cfg, None, reference, 7 + k)))
        seen.append(k)
        return Solved(objectives[k], converged[k])

    monkeypatch.setattr(starts, "run_predict", fake_run)
    with workers(1) as here:
        results = studies.run_starts(cfg, here, params=None, reference=reference, init=given)
    assert seen == [0, 1, 2, 3] and [r.objective for r in results] == [10.0, 10.05, 9.0, 8.0]
    agreed, best = starts.agreeing(results)
    assert best.objective == 9.0 and agreed == 1  # start 3 is lower but unconverged
    assert starts.agreeing([Solved(9.0, True), Solved(9.05, True), Solved(9.2, True)])[0] == 2


def test_a_study_file_is_checked_by_the_predict_stages_validator():
    data = {"speeds_m_s": [1.0, 1.2], "weights": ["b", "3/2,1/2", [1, 1]], "conditions": ["normal", "foot_mass"],
            "nodes": 12, "max_iterations": 40}
    spec = studies.StudySpec.from_mapping(data, "study.yaml")
    assert spec.weights == (("b", (4 / 3, 2 / 3)), ("3/2,1/2", (1.5, 0.5)), ("a", (1.0, 1.0)))
    assert spec.base == PredictConfig(nodes=12, max_iterations=40) and spec.foot_mass_kg == 2.0
    (chain, _) = studies.study_cases(spec)
    assert [c.name for c in chain[:4]] == ["v1.00_b_normal", "v1.00_b_foot_mass", "v1.00_3_2-1_2_normal",
                                           "v1.00_3_2-1_2_foot_mass"]
    assert studies.width(chain) == 2  # each weight set's foot mass beside the next set's normal case
    for change, message in [({"nodes": 13}, "study.yaml: nodes: got 13 (expected an even number"),
                            ({"weights": ["1,2"]}, "study.yaml: weights: got '1,2' (expected two weights"),
                            ({"foot_mass_kg": -1}, "study.yaml: foot_mass_kg: got -1"),
                            ({"speed_m_s": [1.0]}, "study.yaml: speed_m_s: unknown key; did you mean 'speeds_m_s'?")]:
        with pytest.raises(InputError) as caught:
            studies.StudySpec.from_mapping({**data, **change}, "study.yaml")
        assert str(caught.value).startswith(message), str(caught.value)


def test_a_study_file_gives_a_speed_its_own_reference_beside_the_study_file(tmp_path):
    # 5.3.3 tracks Winter's slow, natural and fast cadence at their speeds: ``references`` maps a speed of the
    # grid to a reference table, its path relative to the study file; a speed not listed, or a file that is not
    # there, is refused naming the key
    (tmp_path / "refs").mkdir()
    (tmp_path / "refs" / "slow.csv").write_text("cycle_pct\n")
    path = tmp_path / "study.yaml"
    data = {"speeds_m_s": [1.0, 1.33], "weights": ["b"], "conditions": ["normal"],
            "references": {1.0: "refs/slow.csv"}}
    spec = studies.StudySpec.from_mapping(data, path)
    assert spec.references == ((1.0, tmp_path / "refs" / "slow.csv"),)
    assert studies.StudySpec.from_mapping({**data, "references": {}}, path).references == ()
    for references, message in [({1.68: "refs/slow.csv"}, "references: got the speed 1.68 (expected one of "
                                                          "speeds_m_s: 1, 1.33)"),
                                ({1.33: "refs/fast.csv"}, "references: 1.33: "),
                                ({1.33: 2}, "references: 1.33: got 2 (expected a reference file)"),
                                (["refs/slow.csv"], "references: got ['refs/slow.csv'] (expected a mapping")]:
        with pytest.raises(InputError) as caught:
            studies.StudySpec.from_mapping({**data, "references": references}, path)
        assert str(caught.value).startswith(f"{path}: {message}"), str(caught.value)


def test_a_bad_reference_of_a_speed_stops_the_study_before_it_writes_anything(tmp_path):
    from gaitcli.run.config import PipelineConfig

    (tmp_path / "refs").mkdir()
    (tmp_path / "refs" / "slow.csv").write_text("cycle_pct,hip_r_flexion_deg_mean\n0,1\n")
    study = tmp_path / "study.yaml"
    study.write_text("speeds_m_s: [1.0]\nweights: [b]\nconditions: [normal]\nreferences: {1.0: refs/slow.csv}\n")
    with pytest.raises(InputError) as caught:
        studies.run_study(None, study, PipelineConfig(), out=tmp_path / "out")
    assert str(caught.value).startswith(f"{tmp_path / 'refs' / 'slow.csv'}: "), str(caught.value)
    assert not (tmp_path / "out").exists()


def test_each_speed_of_a_study_tracks_its_own_reference_and_stride(tmp_path):
    # without references: each speed the shipped reference of its own speed, the stride bounded by its group's
    # (± 1 SD); a speed listed in references: that file, the stride in the box; the case keys differ by speed
    from gaitcli.predict.model import WalkerParameters
    from gaitcli.predict.speed_reference import speed_reference
    from gaitcli.run.stages import PredictionInputs

    params = WalkerParameters.subject_1()
    spec = studies.StudySpec.from_mapping({"speeds_m_s": [1.0, 1.33, 1.68], "weights": ["b"],
                                           "conditions": ["normal", "sach"]}, tmp_path / "study.yaml")
    cases = [case for chain in studies.study_cases(spec) for case in chain]
    own = read_reference(bundled_reference())
    bounded, tracked = studies.tracked_cases(cases, PredictionInputs(params, None), {1.68: own})
    by_name = {case.name: case for case in bounded}
    for speed in (1.0, 1.33):
        expected = speed_reference(speed, params.leg_length_m)
        for case in (c for c in bounded if c.speed_m_s == speed):
            assert tracked[case.name].digest() == expected.reference.digest()
            low, high = case.cfg.stride_range_m
            assert low == pytest.approx(expected.stride_m - expected.stride_sd_m, abs=1e-4)
            assert high == pytest.approx(expected.stride_m + expected.stride_sd_m, abs=1e-4)
    fast = [c for c in bounded if c.speed_m_s == 1.68]
    assert all(tracked[c.name] is own and c.cfg.stride_range_m is None for c in fast)
    keys = {studies.case_key(by_name[name], "subject 1", tracked[name].digest(), ())
            for name in ("v1.00_b_normal", "v1.33_b_normal", "v1.68_b_normal")}
    assert len(keys) == 3
    # a run's own reference (--reference, a trial's strides) is every speed's, the stride in the box
    _, given = studies.tracked_cases(cases, PredictionInputs(params, own), {})
    assert all(reference is own for reference in given.values())


def test_an_unconverged_case_starts_again_from_its_nearest_converged_neighbour():
    # the prosthesis grid, every case converged but 1.33 m/s a) SACH and Seattle and b) SACH; Seattle a) from
    # Seattle b) (the next weight set at its speed), SACH a) from SACH c) (b) did not converge either), b) SACH
    # from SACH c) (as near as a), which is later); with no converged SACH at 1.33 m/s, from 1.00 m/s a)
    cases = [c for chain in studies.study_cases(spec_of("prostheses")) for c in chain]
    failed = {"v1.33_a_sach", "v1.33_a_seattle", "v1.33_b_sach"}
    results = {c.name: Solved(1.0, c.name not in failed) for c in cases}
    by_name = {c.name: c for c in cases}
    again = {name: studies.retry_start(by_name[name], cases, results) for name in sorted(failed)}
    assert again == {"v1.33_a_sach": "v1.33_c_sach", "v1.33_a_seattle": "v1.33_b_seattle",
                     "v1.33_b_sach": "v1.33_c_sach"}
    assert all(studies.retry_start(c, cases, results) is None for c in cases if c.name not in failed)
    for name in ("v1.33_c_sach", "v1.33_d_sach"):
        results[name] = Solved(1.0, False)
    assert studies.retry_start(by_name["v1.33_a_sach"], cases, results) == "v1.00_a_sach"
    results["v1.33_a_optimal"] = Solved(1.0, False)  # the optimal device starts from the feet, not again
    assert studies.retry_start(by_name["v1.33_a_optimal"], cases, results) is None


@pytest.mark.parametrize("converges", [True, False])
def test_a_case_started_again_replaces_the_first_try_only_where_it_converges(monkeypatch, tmp_path, converges):
    cases = {c.name: c for chain in studies.study_cases(spec_of("prostheses")) for c in chain}
    case, neighbour = cases["v1.33_a_sach"], "v1.33_b_sach"
    first_try = (Solved(39.4, False), "first key", {"wall_time_s": 150.0, "problems_built": 1, "build_time_s": 2.0})
    started = (Solved(14.7, True), "neighbour key", {})
    solved, written = [], []

    def fake_solve(again, solutions, params, reference):
        solved.append((again.starts_from, solutions[neighbour]))
        return Solved(18.9, converges), 1

    monkeypatch.setattr(studies, "_solve_case", fake_solve)
    monkeypatch.setattr(studies, "write_case", lambda folder, result, attrs, extra: written.append((folder, extra)))
    monkeypatch.setattr(studies, "provenance", lambda *a: {})
    monkeypatch.setattr(studies, "case_row", lambda c, r, **k: {"case": c.name, "objective": r.objective, **k})
    reference = read_reference(bundled_reference())
    out = studies.retry_case(case, str(tmp_path), None, reference, "subject", studies.PipelineConfig(), {}, False,
                             first_try, neighbour, started)
    assert solved == [((neighbour,), started[0])]
    if not converges:
        assert out is first_try and written == []
        return
    result, key, row = out
    assert result.objective == 18.9 and key != "first key" and row["started_again_from"] == neighbour
    (folder, extra), = written
    assert folder == tmp_path / case.name and extra["replaces_key"] == "first key" and extra["case_key"] == key
    # a rerun asks for the first try's key: the folder answers with the retried result
    (tmp_path / case.name).mkdir()
    (tmp_path / case.name / "summary.json").write_text(f'{{"case_key": "{key}", "replaces_key": "first key"}}')
    monkeypatch.setattr(studies, "read_result", lambda path, kind: ("read", path.parent.name))
    assert studies.stored_case(tmp_path / case.name, "first key") == ("read", case.name)
    assert studies.stored_case(tmp_path / case.name, "another key") is None


def test_a_study_starts_an_unconverged_case_again_and_lists_it(monkeypatch, tmp_path):
    # weights a) then b) at one speed: a) does not converge from the default start, b) from a)'s end does; a) is
    # then solved again from b)'s solution, which converges, and study.csv says where it started again
    (tmp_path / "two.yaml").write_text("name: two\nspeeds_m_s: [1.1275]\nweights: [a, b]\nconditions: [normal]\n"
                                       "nodes: 6\n")
    calls = []

    def fake_solve(case, solutions, params, reference):
        calls.append((case.name, tuple(solutions)))
        return Solved(5.0, case.weight_set == "b" or bool(solutions and "b" in next(iter(solutions)))), 1

    monkeypatch.setattr(studies, "_solve_case", fake_solve)
    monkeypatch.setattr(studies, "write_case", lambda folder, result, attrs, extra: None)
    monkeypatch.setattr(studies, "provenance", lambda *a: {})
    monkeypatch.setattr(studies, "case_row", lambda c, r, **k: {"case": c.name, "converged": r.converged,
                                                                  "wall_time_s": 1.0, "problems_built": 0,
                                                                  "build_time_s": 0.0})
    import gaitcli.report.study_plots as plots
    monkeypatch.setattr(plots, "study_figures", lambda *a, **k: None)
    rows, folder = studies.run_study(None, tmp_path / "two.yaml", studies.PipelineConfig(), out=tmp_path / "out",
                                     workers_count=1)
    assert calls == [("v1.13_a_normal", ()), ("v1.13_b_normal", ("v1.13_a_normal",)),
                     ("v1.13_a_normal", ("v1.13_b_normal",))]
    assert [(r["case"], r["converged"], r["started_again_from"]) for r in rows] == \
        [("v1.13_a_normal", True, "v1.13_b_normal"), ("v1.13_b_normal", True, "")]
    assert "started_again_from" in (folder / "study.csv").read_text().splitlines()[0]
