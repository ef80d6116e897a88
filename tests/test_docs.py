"""The documentation (docs/, Sphinx): it builds with warnings as errors, every command has its page and the API
reference lists every public name. Its examples run in tests/test_api.py."""

from __future__ import annotations

import re
import subprocess
import sys
from pathlib import Path

import gaitcli

DOCS = Path(__file__).resolve().parents[1] / "docs"


def test_the_documentation_builds_without_a_warning(tmp_path):
    done = subprocess.run([sys.executable, "-m", "sphinx", "-W", "--keep-going", "-q", "-b", "html", str(DOCS),
                           str(tmp_path / "html")], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr[-4000:]
    api = (tmp_path / "html" / "api.html").read_text(encoding="utf-8")
    assert all(f'id="gaitcli.{name}"' in api for name in gaitcli.__all__)
    assert "--cutoff" in (tmp_path / "html" / "commands" / "filter.html").read_text(encoding="utf-8")


def test_every_command_has_a_page_generated_from_its_options():
    from gaitcli.cli import gait

    pages = {p.stem: p.read_text(encoding="utf-8") for p in (DOCS / "commands").glob("*.rst") if p.stem != "index"}
    assert set(pages) == set(gait.commands)
    for name, command in gait.commands.items():
        assert re.search(rf"^\.\. click:: gaitcli\.cli:{command.callback.__name__}\n   :prog: gait {name}$",
                         pages[name], re.M), name
        assert f"   {name}\n" in (DOCS / "commands" / "index.rst").read_text(encoding="utf-8")


def test_the_api_reference_lists_every_public_name():
    text = (DOCS / "api.rst").read_text(encoding="utf-8")
    listed = re.findall(r"^\.\. auto(?:function|class|exception):: (\w+)$", text, re.M)
    assert sorted(listed) == sorted(gaitcli.__all__) and len(listed) == len(set(listed))
