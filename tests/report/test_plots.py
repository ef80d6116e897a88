"""Figures drawn from small HDF5 files of known content (tests/report/synthetic.py): what each axis shows, in
which unit, and the values of the curves, without running a stage."""

from __future__ import annotations

import matplotlib.pyplot as plt
import numpy as np
import pytest

from gaitcli.errors import InputError
from gaitcli.report import plots
from gaitcli.signal.bands import CYCLE_PCT, Band

from . import synthetic

P = np.arange(101.0)  # the cycle's percentages
INSIDE_LEFT_UNKNOWN = (P > 30) & (P < 70)  # the left stride 0.6-1.6 s: load unknown 0.9-1.3 s (±1 % at the edges)
OUTSIDE_LEFT_UNKNOWN = (P < 29) | (P > 71)


def lines(ax) -> dict:
    """The labelled curves of an axis by their legend label."""
    return {line.get_label(): line for line in ax.get_lines() if not line.get_label().startswith("_")}


@pytest.fixture
def idyn_h5(tmp_path):
    return synthetic.write_idyn(tmp_path / "idyn.h5")


@pytest.fixture
def drawn(monkeypatch):
    """The figures the figure functions save, by file name, kept open for inspection."""
    figures = {}

    def keep(fig, path):
        figures[path.name] = fig
        return path
    monkeypatch.setattr(plots, "save", keep)
    yield figures
    for fig in figures.values():
        plt.close(fig)


def test_cycle_figure_labels_every_axis_with_its_unit(idyn_h5):
    fig = plots.cycle_figure(idyn_h5, "sagittal", title="walk")
    axes = np.array(fig.axes).reshape(3, 3)
    for row, unit in enumerate(("(deg)", "(N·m/kg)", "(W/kg")):
        assert all(unit in ax.get_ylabel() for ax in axes[row]), [ax.get_ylabel() for ax in axes[row]]
    assert [ax.get_xlabel() for ax in axes[-1]] == ["gait cycle (%)"] * 3
    assert [ax.get_title() for ax in axes[0]] == ["hip flexion", "knee flexion", "ankle dorsiflexion"]
    assert axes[1, 0].get_ylabel() == "hip extensor moment (N·m/kg)"  # Plug-in Gait's sense, from the columns
    assert "Plug-in Gait" in fig._suptitle.get_text()
    plt.close(fig)


def test_cycle_figure_has_one_mean_curve_per_side_counting_its_strides(idyn_h5):
    fig = plots.cycle_figure(idyn_h5, "sagittal")
    right = sum(s.side == "r" for s in synthetic.STRIDES)
    left = sum(s.side == "l" for s in synthetic.STRIDES)
    assert (right, left) == (2, 1)
    for ax in fig.axes:
        assert set(lines(ax)) == {f"right (n={right})", f"left (n={left})"}
    plt.close(fig)


def test_cycle_figure_curves_are_the_stride_means(idyn_h5):
    fig = plots.cycle_figure(idyn_h5, "sagittal")
    axes = np.array(fig.axes).reshape(3, 3)
    hip, knee = lines(axes[0, 0]), lines(axes[1, 1])
    # hip flexion 20 sin(2π(t − 0.1)) + 5 t: the right strides start at 0.1 and 1.1 s, the left at 0.6 s
    np.testing.assert_allclose(hip["right (n=2)"].get_ydata(), 20 * np.sin(2 * np.pi * P / 100) + 5 * (0.6 + P / 100),
                               atol=1e-9)
    np.testing.assert_allclose(hip["left (n=1)"].get_ydata(), -20 * np.sin(2 * np.pi * P / 100) + 5 * (0.6 + P / 100),
                               atol=1e-9)
    # knee moment 7 t N·m at 70 kg: 0.1 t N·m/kg; the left blank where its load is unknown
    np.testing.assert_allclose(knee["right (n=2)"].get_ydata(), 0.1 * (0.6 + P / 100), atol=1e-12)
    left_knee = knee["left (n=1)"].get_ydata()
    assert np.isnan(left_knee[INSIDE_LEFT_UNKNOWN]).all()
    np.testing.assert_allclose(left_knee[OUTSIDE_LEFT_UNKNOWN], 0.1 * (0.6 + P[OUTSIDE_LEFT_UNKNOWN] / 100), atol=1e-12)
    # hip moment 70 N·m and power 140 W at 70 kg
    np.testing.assert_allclose(lines(axes[1, 0])["right (n=2)"].get_ydata(), 1.0)
    np.testing.assert_allclose(lines(axes[2, 0])["right (n=2)"].get_ydata(), 2.0)
    left_power = lines(axes[2, 0])["left (n=1)"].get_ydata()
    assert np.isnan(left_power[INSIDE_LEFT_UNKNOWN]).all() and np.all(left_power[OUTSIDE_LEFT_UNKNOWN] == 2.0)
    plt.close(fig)


def test_frontal_figure_and_files_without_powers_have_no_power_row(tmp_path, idyn_h5):
    fig = plots.cycle_figure(idyn_h5, "frontal")
    assert len(fig.axes) == 6 and fig.axes[3].get_ylabel() == "hip abductor moment (N·m/kg)"
    plt.close(fig)
    fig = plots.cycle_figure(synthetic.write_idyn(tmp_path / "older.h5", powers=False), "sagittal")
    assert len(fig.axes) == 6
    plt.close(fig)


def test_coordinate_moments_are_labelled_by_their_own_sense(tmp_path):
    fig = plots.cycle_figure(synthetic.write_idyn(tmp_path / "idyn.h5", moments="coordinate"), "sagittal")
    assert fig.axes[3].get_ylabel() == "hip flexion moment (N·m/kg)"
    assert "Plug-in Gait" not in fig._suptitle.get_text()
    plt.close(fig)


def test_the_normal_band_is_drawn_where_it_has_the_variable(idyn_h5):
    mean, sd = 30 + 0.1 * CYCLE_PCT, np.full(101, 4.0)
    band = Band({"hip_flexion_deg": mean}, {"hip_flexion_deg": sd}, "test band")
    fig = plots.cycle_figure(idyn_h5, "sagittal", band=band)
    hip, knee = fig.axes[0], fig.axes[1]
    (fill,) = [c for c in hip.collections if c.get_label() == "normal ± 1 SD"]
    low, high = fill.get_paths()[0].vertices[:, 1].min(), fill.get_paths()[0].vertices[:, 1].max()
    assert (low, high) == pytest.approx(((mean - sd).min(), (mean + sd).max()))
    dotted = [line for line in hip.get_lines() if line.get_linestyle() == ":"]
    assert len(dotted) == 1 and np.array_equal(dotted[0].get_ydata(), mean)
    assert not [c for c in knee.collections if c.get_label() == "normal ± 1 SD"]  # no knee in this band
    assert "grey: normal ± 1 SD" in fig._suptitle.get_text()
    plt.close(fig)
    fig = plots.cycle_figure(idyn_h5, "sagittal", band=None)
    assert "normal" not in fig._suptitle.get_text()
    plt.close(fig)


def test_idyn_figures_blank_the_residuals_where_a_foot_stood_off_the_plates(idyn_h5, tmp_path, drawn):
    written = plots.idyn_figures(idyn_h5, tmp_path / "plots", title="walk", band=None)
    assert [p.name for p in written] == ["cycle.png", "cycle_frontal.png", "residuals.png"]
    force, moment = drawn["residuals.png"].axes
    assert (force.get_ylabel(), moment.get_ylabel()) == ("pelvis residual force (N)", "pelvis residual moment (N·m)")
    assert [line.get_label() for line in force.get_lines()] == ["x", "y", "z"]
    x = force.get_lines()[0].get_ydata()
    assert np.isnan(x[synthetic.LEFT_UNKNOWN]).all()
    np.testing.assert_array_equal(x[~synthetic.LEFT_UNKNOWN], synthetic.TIME_S[~synthetic.LEFT_UNKNOWN])
    np.testing.assert_array_equal(moment.get_lines()[1].get_ydata()[~synthetic.LEFT_UNKNOWN],
                                  -synthetic.TIME_S[~synthetic.LEFT_UNKNOWN])
    # events: right heel strikes (3) and toe offs (2), left heel strikes (2) and toe off (1), one collection each
    marks = [c for c in force.collections if c.get_label() != "a foot on the ground off the plates"
             and len(c.get_segments())]
    assert sorted(len(c.get_segments()) for c in marks) == [1, 2, 2, 3]


def test_filter_figures_show_raw_and_filtered_markers_in_mm(tmp_path, drawn):
    written = plots.filter_figures(synthetic.write_filter(tmp_path / "filter.h5"), tmp_path / "plots", title="walk")
    assert [p.name for p in written] == ["markers.png", "grf.png"]
    axes = np.array(drawn["markers.png"].axes).reshape(-1, 2)
    wanted = ["CAr", "FMr", "CAl", "FMl"]  # the feet first, four at most, in the figure's order of preference
    assert [ax.get_ylabel() for ax in axes[:, 0]] == [f"{m} forward x (mm)" for m in wanted]
    assert all(ax.get_ylabel().endswith("vertical z (mm)") for ax in axes[:, 1])
    raw, filtered = axes[1, 0].get_lines()[:2]  # FMr forward: marker 2 at x = 2 m, raw 1 mm ahead
    np.testing.assert_allclose(filtered.get_ydata(), 2000.0)
    np.testing.assert_allclose(raw.get_ydata(), 2001.0)
    np.testing.assert_allclose(axes[0, 1].get_lines()[1].get_ydata(), 1000 * synthetic.TIME_S)
    assert f"{synthetic.CUTOFF_HZ:g} Hz" in drawn["markers.png"]._suptitle.get_text()


def test_grf_figure_shows_each_foot_on_the_plates_and_the_unfiltered_plates(tmp_path, drawn):
    plots.filter_figures(synthetic.write_filter(tmp_path / "filter.h5"), tmp_path / "plots")
    vertical, fore_aft, lateral, cop = drawn["grf.png"].axes
    assert [ax.get_ylabel() for ax in (vertical, fore_aft, lateral, cop)] == [
        "vertical GRF\n(N)", "fore-aft GRF\n(N)", "mediolateral, + left GRF\n(N)", "COP forward x (m)"]
    curves = vertical.get_lines()
    assert [line.get_label() for line in curves[:1]] == ["right"]  # the left foot was never on a plate
    assert np.nanmax(curves[0].get_ydata()) == 700.0
    unfiltered = curves[1]  # one plate, at the analog rate
    assert unfiltered.get_xdata().size == 2200
    assert unfiltered.get_xdata()[-1] == pytest.approx(2199 / synthetic.ANALOG_RATE_HZ)
    # events as in the idyn figure: 3 + 2 right, 2 + 1 left
    assert sorted(len(c.get_segments()) for c in vertical.collections) == [1, 2, 2, 3]


def test_given_the_body_mass_the_grf_is_in_percent_of_body_weight(tmp_path, drawn):
    plots.filter_figures(synthetic.write_filter(tmp_path / "filter.h5"), tmp_path / "plots", body_mass_kg=70.0)
    vertical = drawn["grf.png"].axes[0]
    assert vertical.get_ylabel() == "vertical GRF\n(% body weight)"
    assert np.nanmax(vertical.get_lines()[0].get_ydata()) == pytest.approx(700.0 / (70.0 * 9.81) * 100)


def test_without_a_foot_on_the_plates_the_grf_figure_shows_the_plates(tmp_path, drawn):
    plots.filter_figures(synthetic.write_filter(tmp_path / "filter.h5", right_on_plates=False), tmp_path / "plots")
    assert lines(drawn["grf.png"].axes[0]).keys() == {"plate1"}


@pytest.mark.parametrize("figures,name", [(plots.filter_figures, "idyn.h5"), (plots.idyn_figures, "filter.h5")])
def test_a_figure_from_another_stage_s_file_is_an_input_error(tmp_path, figures, name):
    path = tmp_path / name
    (synthetic.write_idyn if name == "idyn.h5" else synthetic.write_filter)(path)
    with pytest.raises(InputError, match=name):
        figures(path, tmp_path / "plots")


def muscle_result(*, metabolic_cost_J: float = 36.0, infeasible_frames=()):
    """A muscle result over 1 s at 50 nodes: muscle k's force 100 k N, activation k/10, excitation k/10;
    metabolic energy k J (k = 1..8, Table A.1's order)."""
    from gaitcli.muscles.stage import MuscleResult

    names = ("iliopsoas", "glutei", "hamstrings", "rectus_femoris", "vasti", "gastrocnemius", "soleus",
             "tibialis_anterior")
    k = np.arange(1, 9.0)
    n = 50
    t = np.linspace(0.1, 1.1, n)
    ones, zeros3 = np.ones((n, 1)), np.zeros((n, 3))
    return MuscleResult(
        method="mso" if infeasible_frames else "eid", objective="effort", side="r", time_s=t, muscle_names=names,
        forces_N=100 * k * ones, activations=k / 10 * ones, excitations=k / 10 * ones, fibre_length_m=0.1 * ones * k,
        fibre_velocity_m_s=0 * ones * k, metabolic_rate_W=k * ones, metabolic_cost_J=metabolic_cost_J,
        metabolic_energy_J=k, cost_of_transport_J_per_m=50.0, ralston_J_per_m=60.0, distance_m=1.2, speed_m_s=1.2,
        duration_s=1.0, joint_moments_Nm=zeros3, passive_moments_Nm=zeros3, damping_moments_Nm=zeros3,
        muscle_moments_Nm=zeros3, moment_error_Nm=zeros3, converged=True, status="Solve_Succeeded", iterations=10,
        solve_time_s=0.1, min_excitation=0.1, max_excitation=0.8, infeasible_frames=tuple(infeasible_frames),
        infeasibility=tuple(0.1 for _ in infeasible_frames), periodic=True, nodes=n, events=synthetic.events())


def write_muscles(path, result):
    from gaitcli.io.h5 import record_datasets, write_h5

    return write_h5(path, record_datasets("result", result), {})


def test_muscle_figures_draw_one_curve_per_muscle_and_its_energy(tmp_path, drawn):
    result = muscle_result()
    written = plots.muscle_figures(write_muscles(tmp_path / "muscles.h5", result), tmp_path / "plots")
    assert [p.name for p in written] == ["forces.png", "activations.png", "excitations.png", "metabolic_cost.png"]
    forces = drawn["forces.png"].axes
    assert [ax.get_title() for ax in forces] == list(result.muscle_names)
    for k, ax in enumerate(forces, start=1):
        (curve,) = ax.get_lines()
        np.testing.assert_array_equal(curve.get_ydata(), 100.0 * k)
    assert {ax.get_ylabel() for ax in forces[::4]} == {"force (N)"} and forces[-1].get_xlabel() == "time (s)"
    assert drawn["activations.png"].axes[0].get_ylim() == (-0.05, 1.05)
    (energy,) = drawn["metabolic_cost.png"].axes
    bars = sorted(energy.patches, key=lambda bar: -bar.get_y())  # from the top: Table A.1's order
    assert [bar.get_width() for bar in bars] == list(np.arange(1, 9.0))
    assert energy.get_xlabel() == "metabolic energy (J)" and "one leg total 36.0 J" in energy.get_title()


def test_muscle_figures_say_where_the_energetics_do_not_apply(tmp_path, drawn):
    result = muscle_result(metabolic_cost_J=float("nan"), infeasible_frames=(10, 30))
    plots.muscle_figures(write_muscles(tmp_path / "muscles.h5", result), tmp_path / "plots")
    (energy,) = drawn["metabolic_cost.png"].axes
    assert not energy.patches and "not given" in energy.get_title()
    assert all(len(ax.patches) == 2 for ax in drawn["forces.png"].axes)  # one red span per infeasible frame
    assert "red: infeasible frames" in drawn["forces.png"]._suptitle.get_text()


def test_foot_off_is_each_sides_mean_toe_off_and_normal_walkings():
    from gaitcli.signal.cycles import Stride

    strides = [Stride("r", 0.0, 1.0, 0.6), Stride("r", 1.0, 2.2, 1.72), Stride("l", 0.5, 1.5, np.nan),
               Stride("l", 1.5, 2.5, 2.1)]  # right 60 % and 60 %; left: one toe off unseen, one at 60 %
    fig, ax = plt.subplots()
    plots.mark_foot_off(ax, strides)
    vertical = sorted((round(float(line.get_xdata()[0]), 9), line.get_color(), line.get_linestyle())
                      for line in ax.get_lines())
    plt.close(fig)
    assert vertical == sorted([(60.0, plots.SIDE_COLOUR["r"], "--"), (60.0, plots.SIDE_COLOUR["l"], "--"),
                               (plots.NORMAL_FOOT_OFF_PCT, "0.55", "-.")])
