"""Every command prints its usage (MNE-style), and an unknown option is a usage error (exit 2)."""

from __future__ import annotations

import pytest

from gaitcli.cli import gait, main

COMMANDS = sorted(gait.commands)


def test_the_commands_of_design_md_that_exist_so_far():
    assert {"filter", "idyn", "muscles", "run", "synth", "compare"} <= set(COMMANDS)


@pytest.mark.parametrize("command", [None, *COMMANDS])
def test_help_prints_usage(command, capsys):
    args = ["--help"] if command is None else [command, "--help"]
    assert main(args) == 0
    out = capsys.readouterr().out
    assert out.startswith("Usage: gait")
    if command is not None:
        assert command in out.splitlines()[0]


def test_unknown_option_is_exit_2(capsys):
    assert main(["filter", "--no-such-option"]) == 2
    assert "No such option" in capsys.readouterr().err


def test_json_prints_one_document_even_when_earlier_stages_run(tmp_path, monkeypatch, capsys):
    import json

    monkeypatch.chdir(tmp_path)  # the bundled sample trial writes ./gait_out
    assert main(["--json", "--quiet", "idyn"]) == 0  # runs filter first: only idyn's summary is printed
    summary = json.loads(capsys.readouterr().out)
    assert summary["dof"] == 27 and "rms_residual_force_N" in summary
    assert (tmp_path / "gait_out" / "filter" / "summary.json").is_file()


def test_global_options_are_taken_after_the_subcommand_too():
    from gaitcli.cli import global_options_first

    assert global_options_first(["idyn", "T", "--json", "-q"]) == ["--json", "-q", "idyn", "T"]
    assert global_options_first(["--debug", "run", "T", "--no-plots"]) == ["--debug", "run", "T", "--no-plots"]
    assert global_options_first(["filter", "--", "-q"]) == ["filter", "--", "-q"]  # a trial named -q


def test_debug_after_the_subcommand_shows_the_traceback(tmp_path, capsys):
    assert main(["filter", str(tmp_path / "none"), "--debug"]) == 2
    err = capsys.readouterr().err
    assert "Traceback" in err and err.strip().splitlines()[-1].startswith("gait: error: ")
