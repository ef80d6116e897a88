"""Every command prints its usage (MNE-style), and an unknown option is a usage error (exit 2)."""

from __future__ import annotations

import pytest

from gaitcli.cli import gait, main

COMMANDS = sorted(gait.commands)


def test_the_commands_of_design_md_that_exist_so_far():
    assert {"filter", "idyn", "muscles", "run", "synth"} <= set(COMMANDS)


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
