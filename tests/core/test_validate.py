"""The shared validators (gaitcli/core/validate.py): messages, ranges and the config-parameter declarations."""

from __future__ import annotations

import dataclasses
from dataclasses import dataclass

import pytest

from gaitcli.core.validate import (
    check_parameter,
    integer,
    known_keys,
    number,
    one_of,
    parameter,
    parameter_spec,
    replace_checked,
)
from gaitcli.errors import InputError


def test_one_of_names_the_choices_and_the_nearest():
    assert one_of("eid", ("so", "mso", "eid"), where="method") == "eid"
    with pytest.raises(InputError) as info:
        one_of("eidd", ("so", "mso", "eid"), where="muscles.method", path="p.yaml")
    assert str(info.value) == "p.yaml: muscles.method: got 'eidd' (expected one of so, mso, eid; did you mean 'eid'?)"
    with pytest.raises(InputError, match=r"got 7 \(expected one of r, l\)$"):
        one_of(7, ("r", "l"), where="side")


def test_unknown_keys_with_and_without_a_close_match():
    with pytest.raises(InputError, match=r"filter.cutof_hz: unknown key; did you mean 'cutoff_hz'\?"):
        known_keys({"cutof_hz": 1}, ("cutoff_hz", "order"), where="filter.")
    with pytest.raises(InputError, match="allowed keys are cutoff_hz, order$"):
        known_keys({"zzz": 1}, ("cutoff_hz", "order"))


@pytest.mark.parametrize("value", [float("nan"), float("inf"), True, "3", None, 0.0, -1])
def test_number_rejects_non_finite_non_numbers_and_out_of_range(value):
    with pytest.raises(InputError):
        number(value, where="x", low=0.0, low_open=True)


def test_number_and_integer_ranges():
    assert number(0, where="x", low=0.0) == 0.0  # closed
    assert integer(4, where="nodes", low=4, high=10) == 4
    with pytest.raises(InputError, match="expected an integer between 4 and 10"):
        integer(11, where="nodes", low=4, high=10)
    with pytest.raises(InputError, match="expected an integer"):
        integer(4.0, where="nodes")


@dataclass(frozen=True)
class Example:
    method: str = parameter("b", choices=("a", "b"), help="Which.")
    count: int = parameter(3, low=1, high=9)
    rate_hz: float = parameter(1.5, low=0.0, low_open=True)
    flag: bool = parameter(False)


def test_parameters_coerce_and_check_by_their_declaration():
    fields = {f.name: f for f in dataclasses.fields(Example)}
    assert parameter_spec(fields["method"])["choices"] == ("a", "b") and parameter_spec(fields["method"])["help"]
    assert check_parameter(fields["rate_hz"], 2, where="e.rate_hz") == 2.0
    assert isinstance(check_parameter(fields["rate_hz"], 2, where="e.rate_hz"), float)
    for name, bad in (("method", "c"), ("count", 0), ("count", 2.5), ("rate_hz", 0.0), ("flag", "yes")):
        with pytest.raises(InputError, match=f"e.{name}: got"):
            check_parameter(fields[name], bad, where=f"e.{name}")
    assert replace_checked(Example(), {"count": 9}, section="e") == Example(count=9)
    with pytest.raises(InputError, match="e.cnt: unknown key; did you mean 'count'"):
        replace_checked(Example(), {"cnt": 9}, section="e")
