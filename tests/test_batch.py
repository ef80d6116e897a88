"""``gait batch`` in this process: a trial whose file cannot be read is that trial's failed row (exit 2), not
the end of the batch. Root reads a file of mode 000, so ``open`` refuses it here as it would for another user
(tests/cli/test_batch_cli.py makes the real file where the tests do not run as root)."""

from __future__ import annotations

import builtins
import errno
import io
import os
import shutil

from gaitcli.resources import sample_trial
from gaitcli.run.batch import plan, run_trial
from gaitcli.run.config import load_pipeline


def test_an_unreadable_trial_file_is_planned_and_fails_in_its_own_rows(tmp_path, monkeypatch):
    lab = tmp_path / "lab"
    shutil.copytree(sample_trial("normal"), lab / "walk", ignore=shutil.ignore_patterns("gait_out", "truth"))
    refused = os.path.realpath(lab / "walk" / "trial.c3d")
    real_open = builtins.open

    def fake_open(file, *args, **kwargs):
        if isinstance(file, (str, os.PathLike)) and os.path.realpath(file) == refused:
            raise PermissionError(errno.EACCES, "Permission denied", str(file))
        return real_open(file, *args, **kwargs)

    monkeypatch.setattr(builtins, "open", fake_open)
    monkeypatch.setattr(io, "open", fake_open)
    cfg = load_pipeline()
    rows, todo = plan(lab, cfg)  # reads every trial's files for its input key
    assert rows == [] and [name for _, name, _, _ in todo] == ["walk"]

    folder, name, key, stale = todo[0]
    failed = run_trial(str(folder), name, cfg, key, stale, plots=False)
    assert {r.status for r in failed} == {"failed"} and {r.exit_code for r in failed} == {2}
    assert "trial.c3d: cannot be read (Permission denied)" in failed[0].reason


def test_a_session_folder_in_a_lab_is_its_walks(tmp_path):
    """``gait batch`` finds a session folder's walks, each a trial of its own (its C3D names it), beside trial
    folders; a walk's key covers its own C3D and the session's subject and static, not the other walks."""
    from gaitcli.run.batch import find_trials, input_key
    from gaitcli.run.config import configure

    lab = tmp_path / "lab"
    shutil.copytree(sample_trial("normal"), lab / "normal", ignore=shutil.ignore_patterns("gait_out"))
    session = lab / "S"
    session.mkdir()
    shutil.copy(sample_trial("normal") / "subject.yaml", session)
    shutil.copy(sample_trial("normal") / "static.c3d", session / "Static 01.c3d")
    for name in ("Walking 01.c3d", "Walking 02.c3d"):
        shutil.copy(sample_trial("normal") / "trial.c3d", session / name)
    assert find_trials(lab) == [lab / "S" / "Walking 01.c3d", lab / "S" / "Walking 02.c3d", lab / "normal"]
    cfg = configure(None)
    before = input_key(session / "Walking 01.c3d", cfg)
    (session / "Walking 02.c3d").write_bytes(b"another walk")
    assert input_key(session / "Walking 01.c3d", cfg) == before
    (session / "Static 01.c3d").write_bytes(b"another static")
    assert input_key(session / "Walking 01.c3d", cfg) != before
