"""Pipeline configuration (gaitcli/run/config.py): defaults, the standard pipeline file, validation, overrides."""

from __future__ import annotations

import dataclasses

import pytest
import yaml

from gaitcli.dynamics.stage import IdynConfig
from gaitcli.emg.stage import EmgConfig
from gaitcli.errors import InputError
from gaitcli.muscles.stage import MusclesConfig
from gaitcli.predict.stage import PredictConfig
from gaitcli.resources import pipeline_file
from gaitcli.run.config import PipelineConfig, configure, load_pipeline, pipeline_from_dict, to_yaml, with_overrides
from gaitcli.signal.stage import FilterConfig

SECTIONS = {"filter": FilterConfig, "idyn": IdynConfig, "emg": EmgConfig, "muscles": MusclesConfig,
            "predict": PredictConfig}


def _error(data, path="p.yaml") -> InputError:
    with pytest.raises(InputError) as info:
        pipeline_from_dict(data, path)
    assert "\n" not in str(info.value) and str(info.value).startswith(path)
    return info.value


# ---------------------------------------------------------------------------------- defaults


def test_every_parameter_has_a_default():
    for cls in (PipelineConfig, *SECTIONS.values()):
        for f in dataclasses.fields(cls):
            assert f.default is not dataclasses.MISSING or f.default_factory is not dataclasses.MISSING, \
                f"{cls.__name__}.{f.name}"
    cfg = PipelineConfig()
    assert cfg.filter.cutoff_hz == "auto" and cfg.filter.force_cutoff_hz == "auto" and cfg.filter.order == 2
    assert cfg.stages == ("filter", "idyn")


def test_defaults_equal_the_standard_pipeline_file():
    path = pipeline_file("standard")
    assert load_pipeline(path) == PipelineConfig() == load_pipeline(None)


def test_standard_pipeline_file_lists_every_parameter():
    # "Every key below is the built-in default": the file documents all of them, with their default values
    data = yaml.safe_load(pipeline_file("standard").read_text())
    assert set(data) == {"stages", *SECTIONS}
    for name, cls in SECTIONS.items():
        assert set(data[name]) == {f.name for f in dataclasses.fields(cls)}, name
        for key, value in data[name].items():  # as the file's text is read: "4/3,2/3" is the default weights
            assert getattr(pipeline_from_dict({name: {key: value}}).section(name), key) == getattr(cls(), key), \
                f"{name}.{key}"


def test_bundled_pipelines_by_name(monkeypatch, tmp_path):
    monkeypatch.chdir(tmp_path)  # a name, not a file in the working folder
    assert load_pipeline("standard") == PipelineConfig()
    eid = load_pipeline("muscles_eid")
    assert eid.stages == ("filter", "idyn", "muscles")
    assert eid.muscles.method == "eid" and eid.muscles.nodes == 50 and eid.muscles.objective == "metabolic"
    assert eid.filter == PipelineConfig().filter and eid.idyn == PipelineConfig().idyn
    with pytest.raises(InputError, match="bundled pipelines: muscles_eid, standard"):
        load_pipeline("muscle_eid")


def test_empty_file_and_empty_sections_give_defaults(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("# nothing\n")
    assert load_pipeline(path) == PipelineConfig()
    assert pipeline_from_dict({"filter": None, "idyn": {}}) == PipelineConfig()


def test_partial_file_keeps_other_defaults(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("stages: [idyn, filter, muscles]\nfilter:\n  cutoff_hz: 8\nmuscles:\n  method: so\n")
    cfg = load_pipeline(path)
    assert cfg.stages == ("filter", "idyn", "muscles")  # run in pipeline order whatever the file's order
    assert cfg.filter == dataclasses.replace(FilterConfig(), cutoff_hz=8.0)
    assert isinstance(cfg.filter.cutoff_hz, float)
    assert cfg.muscles == dataclasses.replace(MusclesConfig(), method="so")
    assert cfg.idyn == IdynConfig()


def test_to_yaml_round_trip():
    cfg = pipeline_from_dict({"stages": ["filter"], "filter": {"cutoff_hz": 4.5, "max_gap_frames": 3},
                              "muscles": {"method": "mso", "side": "l", "validate": True}})
    assert pipeline_from_dict(yaml.safe_load(to_yaml(cfg))) == cfg
    assert pipeline_from_dict(yaml.safe_load(to_yaml(PipelineConfig()))) == PipelineConfig()


def test_zero_cutoff_turns_filtering_off():
    assert pipeline_from_dict({"filter": {"cutoff_hz": 0, "force_cutoff_hz": 0}}).filter.cutoff_hz == 0.0


# ------------------------------------------------------------------------------ unknown keys


@pytest.mark.parametrize("data,field,hint", [
    ({"filters": {}}, "filters", "filter"),
    ({"stage": ["filter"]}, "stage", "stages"),
    ({"filter": {"cutof_hz": 8}}, "filter.cutof_hz", "cutoff_hz"),
    ({"filter": {"max_gap": 5}}, "filter.max_gap", "max_gap_frames"),
    ({"idyn": {"frame": "anatomical"}}, "idyn.frame", "frames"),
    ({"muscles": {"methods": "so"}}, "muscles.methods", "method"),
])
def test_unknown_key_did_you_mean(data, field, hint):
    err = _error(data)
    assert err.field == field and "unknown key" in err.problem and f"did you mean '{hint}'" in err.problem


def test_unknown_key_without_a_close_match_lists_the_allowed_keys():
    err = _error({"filter": {"wavelet": "db4"}})
    assert err.field == "filter.wavelet" and "did you mean" not in err.problem
    for f in dataclasses.fields(FilterConfig):
        assert f.name in err.problem


# ---------------------------------------------------------------------------------- bad values


@pytest.mark.parametrize("section,key,value", [
    ("filter", "cutoff_hz", "six"), ("filter", "cutoff_hz", True), ("filter", "cutoff_hz", -1),
    ("filter", "cutoff_hz", float("nan")), ("filter", "cutoff_hz", float("inf")), ("filter", "cutoff_hz", [6]),
    ("filter", "force_cutoff_hz", -0.5), ("filter", "order", 2.5), ("filter", "order", 0), ("filter", "order", True),
    ("filter", "max_gap_frames", -1), ("filter", "max_gap_frames", 10.0), ("filter", "force_threshold_N", 0),
    ("filter", "force_threshold_N", float("nan")), ("idyn", "frames", "segment"), ("idyn", "gravity_m_s2", 0),
    ("idyn", "gravity_m_s2", 1e300), ("idyn", "gravity_m_s2", 1.62),
    ("idyn", "gravity_m_s2", float("nan")), ("muscles", "method", "cmc"), ("muscles", "side", "right"),
    ("muscles", "nodes", 0), ("muscles", "validate", "yes"), ("muscles", "validate", 1),
    ("muscles", "objective", "effort"), ("predict", "weights", "1,2"), ("predict", "weights", [1, "x"]),
    ("predict", "weights", "4/0,2"), ("predict", "nodes", 17), ("predict", "monotone_range_deg", [10, -5]),
    ("predict", "monotone_range_deg", "-25"), ("predict", "foot_mass_at", [1, 2]), ("predict", "prosthesis", "carbon"),
    ("predict", "prosthesis", "absent.yaml"), ("predict", "starts", 0), ("predict", "symmetric", "no"),
])
def test_bad_values(section, key, value):
    err = _error({section: {key: value}})
    assert err.field == f"{section}.{key}" and "expected" in err.problem


@pytest.mark.parametrize("data,field", [
    ({"stages": "filter"}, "stages"), ({"stages": ["filter", "predicts"]}, "stages"), ({"filter": 6}, "filter"),
    ({"filter": ["cutoff_hz", 6]}, "filter"),
])
def test_bad_structure(data, field):
    assert _error(data).field == field


@pytest.mark.parametrize("data", [["filter"], "filter", 3])
def test_not_a_mapping(data):
    assert _error(data).field is None


def test_load_pipeline_file_errors(tmp_path):
    with pytest.raises(InputError, match="nowhere.yaml: pipeline file not found"):
        load_pipeline(tmp_path / "nowhere.yaml")
    path = tmp_path / "p.yaml"
    path.write_text("filter:\n  cutoff_hz: [6\n")
    with pytest.raises(InputError, match=r"p.yaml: line \d+: not valid YAML"):
        load_pipeline(path)
    path.write_bytes(b"\x89PNG\r\n\x1a\n\x00\xff")
    with pytest.raises(InputError, match="p.yaml: not a text file"):
        load_pipeline(path)


# ---------------------------------------------------------------------------------- overrides


def test_overrides_replace_only_given_options():
    base = pipeline_from_dict({"filter": {"cutoff_hz": 7.0, "max_gap_frames": 4}})
    cfg = with_overrides(base, "filter", cutoff_hz=8, force_cutoff_hz=None)
    assert cfg.filter == dataclasses.replace(base.filter, cutoff_hz=8.0)
    assert base.filter.cutoff_hz == 7.0  # the input is not modified
    assert with_overrides(base, "filter", cutoff_hz=None) is base
    assert cfg.idyn == base.idyn and cfg.stages == base.stages


def test_cli_overrides_the_pipeline_file(tmp_path):
    path = tmp_path / "p.yaml"
    path.write_text("filter:\n  cutoff_hz: 7.0\n  force_cutoff_hz: 7.0\n  order: 2\n")
    assert configure(path).filter.cutoff_hz == 7.0  # the file overrides the defaults
    cfg = configure(path, filter={"cutoff_hz": 8.0, "force_cutoff_hz": 8.0})  # what `gait filter --cutoff 8` does
    assert (cfg.filter.cutoff_hz, cfg.filter.force_cutoff_hz) == (8.0, 8.0)
    assert configure(path, filter={"cutoff_hz": None, "force_cutoff_hz": None}).filter.cutoff_hz == 7.0
    assert configure(None, filter={"cutoff_hz": 8.0}).filter == dataclasses.replace(FilterConfig(), cutoff_hz=8.0)


@pytest.mark.parametrize("options,field", [({"cutoff_hz": -1.0}, "filter.cutoff_hz"),
                                           ({"cutoff_hz": float("nan")}, "filter.cutoff_hz"),
                                           ({"cutof_hz": 8.0}, "filter.cutof_hz")])
def test_bad_overrides_are_input_errors(options, field):
    with pytest.raises(InputError) as info:
        with_overrides(PipelineConfig(), "filter", **options)
    assert info.value.field == field and str(info.value).startswith("command line")


def test_configs_are_frozen():
    cfg = PipelineConfig()
    with pytest.raises(dataclasses.FrozenInstanceError):
        cfg.filter.cutoff_hz = 8.0


def test_an_empty_stage_list_is_an_error():
    from gaitcli.errors import InputError
    from gaitcli.run.config import pipeline_from_dict

    with pytest.raises(InputError, match="non-empty list"):
        pipeline_from_dict({"stages": []}, "p.yaml")


def test_a_resolved_configuration_pickles(tmp_path):
    # a batch runner sends it to worker processes
    import pickle

    cfg = configure("muscles_eid", muscles={"method": "so"})
    back = pickle.loads(pickle.dumps(cfg))
    assert back == cfg and back.muscles.method == "so" and back.stages == ("filter", "idyn", "muscles")


def test_the_predict_section_is_parsed_once_into_numbers_and_pairs():
    cfg = pipeline_from_dict({"stages": ["predict"], "predict": {"weights": "8/5,2/5", "monotone_range_deg": "-20,5",
                                                                 "foot_mass_at": [0.1, 0.02], "prosthesis": "SACH"}})
    assert cfg.stages == ("predict",)
    assert cfg.predict.weights == (8 / 5, 2 / 5) and cfg.predict.monotone_range_deg == (-20.0, 5.0)
    assert cfg.predict.foot_mass_at == (0.1, 0.02) and cfg.predict.prosthesis == "sach"
    assert pipeline_from_dict(yaml.safe_load(to_yaml(cfg))) == cfg


@pytest.mark.parametrize("value,kept", [("auto", "auto"), (" Auto", "auto"), (0, 0.0), ("8", 8.0), (12.5, 12.5)])
def test_a_cut_off_is_hz_or_auto(value, kept):
    cfg = pipeline_from_dict({"filter": {"cutoff_hz": value, "force_cutoff_hz": value}})
    assert cfg.filter.cutoff_hz == kept and cfg.filter.force_cutoff_hz == kept
