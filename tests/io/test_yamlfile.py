"""Reading untrusted YAML (gaitcli/io/yamlfile.py): bounded size and alias expansion, duplicate keys refused,
YAML 1.2 exponents, one-line errors."""

from __future__ import annotations

import pytest
import yaml

from gaitcli.errors import InputError
from gaitcli.io.yamlfile import MAX_EXPANDED_NODES, MAX_YAML_BYTES, _expanded_size, read_yaml


def _write(tmp_path, text: str, name="subject.yaml"):
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


def test_plain_document(tmp_path):
    data = read_yaml(_write(tmp_path, "mass_kg: 70.5\nsex: female\nlegs: [r, l]\n"))
    assert data == {"mass_kg": 70.5, "sex": "female", "legs": ["r", "l"]}


@pytest.mark.parametrize("text,value", [("1.0e12", 1.0e12), ("1e12", 1e12), ("-2.5E-3", -2.5e-3), ("3e0", 3.0),
                                        ("1.0e+12", 1.0e12), ("12", 12), ("0.5", 0.5), ("e12", "e12")])
def test_numbers_as_yaml_1_2_reads_them(tmp_path, text, value):
    got = read_yaml(_write(tmp_path, f"x: {text}\n"))["x"]
    assert got == value and type(got) is type(value)


def test_duplicate_keys_are_refused(tmp_path):
    path = _write(tmp_path, "mass_kg: 70\nsex: male\nmass_kg: 80\n")
    with pytest.raises(InputError, match=r"subject.yaml: line 3: key 'mass_kg' given twice") as info:
        read_yaml(path)
    assert "\n" not in str(info.value)


def test_nested_duplicates_are_refused(tmp_path):
    with pytest.raises(InputError, match="key 'order' given twice"):
        read_yaml(_write(tmp_path, "filter:\n  order: 2\n  order: 4\n"))


def test_an_alias_bomb_is_refused_with_a_short_line(tmp_path):
    """Nine levels of nine aliases: 300 bytes that expand to 9⁹ ≈ 4e8 values."""
    lines = ['a: &a ["x","x","x","x","x","x","x","x","x"]']
    for k in range(1, 9):
        prev, cur = chr(ord("a") + k - 1), chr(ord("a") + k)
        lines.append(f"{cur}: &{cur} [" + ",".join([f"*{prev}"] * 9) + "]")
    path = _write(tmp_path, "\n".join(lines) + "\n")
    assert path.stat().st_size < 400
    with pytest.raises(InputError, match=f"aliases expand it beyond {MAX_EXPANDED_NODES:,}") as info:
        read_yaml(path)
    assert len(str(info.value)) < 200
    # the count stops past the limit and visits each shared node once: ~90 nodes, not 4e8
    sizes = {}
    assert _expanded_size(yaml.compose(path.read_text()), sizes, MAX_EXPANDED_NODES) > MAX_EXPANDED_NODES
    assert len(sizes) < 100


def test_a_few_aliases_are_fine(tmp_path):
    data = read_yaml(_write(tmp_path, "base: &b {order: 2}\nfilter: *b\nother: *b\n"))
    assert data["filter"] == data["other"] == {"order": 2}


def test_an_oversized_file_is_refused_before_parsing(tmp_path):
    path = _write(tmp_path, "# " + "x" * MAX_YAML_BYTES + "\nmass_kg: 70\n")
    with pytest.raises(InputError, match="bytes \\(expected a YAML file of at most 1,000,000 bytes\\)"):
        read_yaml(path)


def test_deep_nesting_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="subject.yaml"):
        read_yaml(_write(tmp_path, "x: " + "[" * 5000 + "]" * 5000 + "\n"))


def test_not_text_and_not_yaml(tmp_path):
    path = tmp_path / "subject.yaml"
    path.write_bytes(b"\xff\xfe\x00bad")
    with pytest.raises(InputError, match="not a text file"):
        read_yaml(path)
    with pytest.raises(InputError, match="line 2: not valid YAML"):
        read_yaml(_write(tmp_path, "a: 1\n  b: [\n"))


@pytest.mark.parametrize("char", ["\0", "\x1b", "\x07", "\x0c"])
def test_a_control_character_is_one_line_naming_its_line(tmp_path, char):
    path = _write(tmp_path, f"a: 1\nb: x{char}y\n")
    with pytest.raises(InputError) as info:
        read_yaml(path)
    assert str(info.value) == f"{path}: line 2: control character U+{ord(char):04X} (expected printable text)"


def test_an_integer_of_thousands_of_digits_is_refused_by_line(tmp_path):
    path = _write(tmp_path, "a: 1\nb: " + "9" * 5000 + "\n")
    with pytest.raises(InputError, match=r"line 2: an integer of 5,000 characters"):
        read_yaml(path)
    assert read_yaml(_write(tmp_path, "b: " + "9" * 400 + "\n"))["b"] == int("9" * 400)  # the validators' turn
