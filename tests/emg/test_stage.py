"""The emg stage (gaitcli/emg/stage.py) on synthetic channels with known truth: envelopes over each
muscle's own strides recover the activation that modulates them, whatever the channel's unit; peak and MVC
normalisation; and bad EMG (a slow analog rate, an empty channel, a clipping channel, an MVC trial without the
channel, a map naming absent channels) stopped or warned with the channel named."""

from __future__ import annotations

import warnings

import numpy as np
import pytest

from gaitcli.core.events import Events
from gaitcli.core.recording import Analogs
from gaitcli.emg.stage import EmgConfig, run_emg
from gaitcli.errors import GaitWarning, InputError
from gaitcli.signal.cycles import CYCLE_PCT

from .test_processing import RATE_HZ, synthetic_emg

PERIOD_S = 1.1
DURATION_S = 6.0
RIGHT_STRIKES = 0.4 + PERIOD_S * np.arange(5)  # 4 complete right strides
LEFT_STRIKES = RIGHT_STRIKES + PERIOD_S / 2  # 4 left, the last ends at 5.35 s


def activation_at(phase):
    """A tibialis-anterior-like activation over the cycle (0–1 from heel strike): bursts at heel strike and
    in swing, 0.05 between."""
    d = lambda c: (phase - c + 0.5) % 1.0 - 0.5  # noqa: E731 (distance on the cycle)
    return 0.05 + 0.9 * np.exp(-(d(0.03) / 0.06) ** 2) + 0.5 * np.exp(-(d(0.7) / 0.08) ** 2)


def phase_of(t, strikes):
    return ((t - strikes[0]) / PERIOD_S) % 1.0


def gait_events() -> Events:
    return Events.concatenate([
        Events.from_times(RIGHT_STRIKES, rate_hz=100, side="r", kind="heel_strike", source="kinematics"),
        Events.from_times(LEFT_STRIKES, rate_hz=100, side="l", kind="heel_strike", source="kinematics"),
        Events.from_times(RIGHT_STRIKES + 0.66, rate_hz=100, side="r", kind="toe_off", source="kinematics"),
        Events.from_times(LEFT_STRIKES[:-1] + 0.66, rate_hz=100, side="l", kind="toe_off", source="kinematics")])


def channels(amplitude_V=(1e-3, 1e-3), units=("V", "mV"), labels=("RTIBA", "LTIBA"), rate_hz=RATE_HZ, seed=0):
    """Two channels: the right and the left tibialis anterior, each modulated by its own foot's activation,
    in ``units`` (a mV channel holds 1000× the volts)."""
    t = np.arange(0, DURATION_S, 1 / rate_hz)
    columns = []
    for k, strikes in enumerate((RIGHT_STRIKES, LEFT_STRIKES)):
        raw = amplitude_V[k] * synthetic_emg(activation_at(phase_of(t, strikes)), seed=seed + k)[:, 0]
        columns.append(raw * (1e3 if units[k] == "mV" else 1.0))
    return Analogs(labels=labels, units=units, rate_hz=rate_hz, values=np.column_stack(columns))


def test_each_muscle_is_averaged_over_its_own_strides_and_recovers_its_activation():
    result = run_emg(channels(), gait_events(), None, EmgConfig())
    assert result.muscles == ("tibialis_anterior_r", "tibialis_anterior_l")  # by the labels' presets
    assert list(result.stride_side).count("r") == 4 and list(result.stride_side).count("l") == 4
    truth = activation_at(CYCLE_PCT / 100)
    for k in range(2):
        mean = result.cycle_mean[:, k]
        assert np.nanmax(mean) == pytest.approx(1.0)  # normalised to the peak of the mean
        assert np.corrcoef(mean, truth)[0, 1] >= 0.95
        assert result.cycle_sd[:, k].max() < 0.3
    # a mV channel of the same amplitude in volts: the same reference, in volts
    assert result.reference_V[1] == pytest.approx(result.reference_V[0], rel=0.1)
    assert 1e-4 < result.reference_V[0] < 1e-3
    # on around heel strike and in swing, off in mid stance
    on = result.cycle_on[:, 0]
    assert on[[0, 2, 70]].min() >= 0.75 and on[[30, 40]].max() <= 0.25


def test_mvc_normalisation_divides_by_the_mvc_trials_steady_envelope():
    # a steady maximal contraction, twice (right) and four times (left) the amplitude of the trial's unit
    # activation: its envelope is amplitude · E|unit Gaussian noise| = amplitude · √(2/π) (band-passed once more
    # by the stage, a little less), the best half second of it at most its ripple (~10 %) above
    t = np.arange(0, 3.0, 1 / RATE_HZ)
    amplitudes = np.array([2e-3, 4e-3])
    steady = [a * synthetic_emg(np.ones(t.size), seed=7 + k)[:, 0] for k, a in enumerate(amplitudes)]
    mvc = Analogs(labels=("RTIBA", "LTIBA"), units=("V", "V"), rate_hz=RATE_HZ, values=np.column_stack(steady))
    result = run_emg(channels(), gait_events(), None, EmgConfig(), mvc=mvc)
    assert result.normalisation == "mvc"
    ratio = result.reference_V / (amplitudes * np.sqrt(2 / np.pi))
    assert np.all((ratio > 0.95) & (ratio < 1.15)), ratio
    peak = run_emg(channels(), gait_events(), None, EmgConfig(normalise="peak"), mvc=mvc)
    assert peak.normalisation == "peak" and np.nanmax(peak.cycle_mean[:, 0]) == pytest.approx(1.0)
    np.testing.assert_allclose(result.cycle_mean * result.reference_V, peak.cycle_mean * peak.reference_V,
                               rtol=1e-12)


def test_a_map_names_the_muscles_and_its_missing_channels_stop_the_stage():
    mapping = {"RTIBA": "soleus_r"}  # a lab's own map wins over the presets, and only its channels are read
    result = run_emg(channels(), gait_events(), mapping, EmgConfig())
    assert result.channels == ("RTIBA",) and result.muscles == ("soleus_r",)
    with pytest.raises(InputError, match="RGAS"):
        run_emg(channels(), gait_events(), {"RGAS": "gastrocnemius_r"}, EmgConfig(), map_source="subject.yaml")


@pytest.mark.parametrize("case", ["slow", "no analogs", "no muscle", "mvc without the channel", "mvc not given",
                                  "not volts"])
def test_bad_emg_input_is_an_input_error_naming_the_channel(case):
    analogs, kwargs, expected = channels(), {}, ""
    if case == "slow":
        analogs = channels(rate_hz=100.0)
        expected = r"ANALOG:RATE.*RTIBA, LTIBA.*100 Hz"
    elif case == "no analogs":
        analogs, expected = None, "no analog channels"
    elif case == "no muscle":
        analogs = channels(labels=("Channel 1", "Channel 2"))
        expected = "no analog channel is named"
    elif case == "mvc without the channel":
        kwargs = {"mvc": channels(labels=("RTIBA", "X"))}
        expected = "emg_mvc.*LTIBA"
    elif case == "mvc not given":
        kwargs, expected = {"cfg": EmgConfig(normalise="mvc")}, "emg_mvc"
    else:
        analogs = channels(units=("V", "N"))
        expected = "ANALOG:UNITS of LTIBA.*'N'"
    cfg = kwargs.pop("cfg", EmgConfig())
    with pytest.raises(InputError, match=expected):
        run_emg(analogs, gait_events(), None, cfg, **kwargs)


@pytest.mark.parametrize("mapping", [None, {"R TA": "tibialis_anterior_r"}])
def test_two_channels_of_one_label_are_refused_naming_both(mapping):
    """Two analog channels labelled "R TA" (issue 53, item 3): before, the second was silently never read."""
    analogs = channels(labels=("R TA", "R TA"))
    with pytest.raises(InputError) as info:
        run_emg(analogs, gait_events(), mapping, EmgConfig(), source="trial.c3d")
    assert (str(info.value.path), info.value.field) == ("trial.c3d", "ANALOG:LABELS")
    assert "channels 1 and 2 are both labelled 'R TA'" in str(info.value)


def test_an_envelope_cutoff_above_nyquist_names_its_option():
    """Issue 53, item 16: before, "cutoff_hz: got 100000.0 Hz", neither the file nor the option named."""
    with pytest.raises(InputError) as info:
        run_emg(channels(), gait_events(), None, EmgConfig(envelope_cutoff_hz=100000.0), source="trial.c3d")
    assert info.value.field == "emg.envelope_cutoff_hz (--envelope-cutoff)"
    assert f"got 100000 Hz (expected below the Nyquist frequency {RATE_HZ / 2:g} Hz" in str(info.value)


def test_a_map_of_2000_absent_channels_lists_a_few():
    """Issue 53, item 16: before, one line of 16 219 characters."""
    mapping = {f"CH{k}": "soleus_r" for k in range(2000)}
    with pytest.raises(InputError) as info:
        run_emg(channels(), gait_events(), mapping, EmgConfig(), map_source="subject.yaml")
    assert "channels CH0, CH1, CH2, CH3, CH4, CH5, CH6, CH7 and 1992 more are not in the trial" in str(info.value)
    assert len(str(info.value)) < 300


def test_an_empty_channel_is_left_out_and_a_clipping_one_is_kept_both_with_a_warning():
    analogs = channels()
    analogs.values[:, 1] = np.nan
    with pytest.warns(GaitWarning, match="LTIBA has no finite sample"):
        result = run_emg(analogs, gait_events(), None, EmgConfig())
    assert result.channels == ("RTIBA",)

    analogs = channels()
    limit = 0.5 * np.abs(analogs.values[:, 0]).max()
    analogs.values[:, 0] = np.clip(analogs.values[:, 0], -limit, limit)
    with pytest.warns(GaitWarning, match="RTIBA clips"):
        result = run_emg(analogs, gait_events(), None, EmgConfig())
    assert result.clipped == ("RTIBA",)
    with warnings.catch_warnings():
        warnings.simplefilter("error", GaitWarning)  # the untouched channels: no warning at all
        assert run_emg(channels(), gait_events(), None, EmgConfig()).clipped == ()
