"""Trial folders: discovery of the files.

A trial folder holds ``trial.c3d`` (or the file ``subject.yaml`` names under
``trial:``, or ``markers.csv`` + ``forces.csv``), an optional ``static.c3d``,
``subject.yaml`` and optionally the lab's Vicon subject file (one ``.vsk``, or the
one ``subject.yaml`` names under ``vsk:``); the subject's schema is
:mod:`gaitcli.kinematics.subject`. Nothing in the folder is ever modified.
"""

from __future__ import annotations

import hashlib
from dataclasses import dataclass
from pathlib import Path

from gaitcli.errors import InputError, shown
from gaitcli.io.vsk import read_vsk
from gaitcli.kinematics.subject import Subject, load_subject, subject_from_vsk, with_measurements


@dataclass(frozen=True)
class TrialFolder:
    """The files of one trial folder, checked to exist."""

    folder: Path
    subject_path: Path  # subject.yaml, or the .vsk when the folder has no subject.yaml
    subject: Subject
    trial_path: Path  # the dynamic C3D, or markers.csv
    forces_path: Path | None = None  # forces.csv when the trial is given as CSV
    static_path: Path | None = None
    vsk_path: Path | None = None  # the Vicon subject file whose parameters are the subject's measurements

    @property
    def name(self) -> str:
        return self.folder.name

    def input_files(self) -> list[Path]:
        paths = (self.subject_path, self.trial_path, self.forces_path, self.static_path, self.vsk_path)
        return list(dict.fromkeys(p for p in paths if p))


def _named_file(folder: Path, name, key: str) -> Path | None:
    """The file ``subject.yaml`` names under ``key`` (None when it names none): a path relative to the trial
    folder that resolves (symlinks followed) to an existing file inside it."""
    if name is None or name == "":
        return None
    subject = folder / "subject.yaml"
    if not isinstance(name, str):
        raise InputError(subject, key, f"got {shown(name)} (expected a file name inside the trial folder)")
    if "\0" in name:
        raise InputError(subject, key, f"got {shown(name)} (expected a file name without NUL characters)")
    path = folder / name
    try:
        inside = folder.resolve()
        if Path(name).is_absolute() or not path.resolve().is_relative_to(inside):
            raise InputError(subject, key, f"names {shown(name)}, which is outside the trial folder {folder} "
                                           "(expected a file inside it)")
        found = path.is_file()
    except OSError as exc:  # a name longer than the system allows (ENAMETOOLONG)
        raise InputError(subject, key, f"names {shown(name)}, which cannot be a file here ({exc.strerror}; "
                                       "expected a file inside the trial folder)") from None
    except RuntimeError:  # Path.resolve on a loop of symbolic links (Python < 3.13)
        raise InputError(subject, key, f"names {shown(name)}, a loop of symbolic links (expected a file inside "
                                       "the trial folder)") from None
    if not found:
        raise InputError(subject, key, f"names {shown(name)}, which is not in {folder}")
    return path


def _found_file(folder: Path, path: Path | None) -> Path | None:
    """``path``, a file found in ``folder`` by its usual name, when it resolves (symlinks followed) inside the
    folder, as a file that ``subject.yaml`` names must."""
    if path is not None and not path.resolve().is_relative_to(folder.resolve()):
        raise InputError(path, None, f"links to {shown(str(path.resolve()))}, which is outside the trial folder "
                                     f"{folder} (expected a file inside it: copy the file in)")
    return path


def _vsk_files(folder: Path) -> list[Path]:
    """The Vicon subject files (``*.vsk``, any case; hidden files not) directly in ``folder``, sorted."""
    return sorted(p for p in folder.iterdir() if p.suffix.lower() == ".vsk" and not p.name.startswith(".")
                  and p.is_file())


def _only_vsk(folder: Path, has_yaml: bool) -> Path | None:
    """The folder's one .vsk (None without); more than one is an error naming them."""
    found = _vsk_files(folder)
    if len(found) > 1:
        names = ", ".join(shown(p.name) for p in found[:4]) + (", …" if len(found) > 4 else "")
        how = "`vsk:` in subject.yaml naming one" if has_yaml else "a subject.yaml naming one under `vsk:`"
        raise InputError(folder, "vsk", f"{len(found)} Vicon subject files: {names} (expected one, or {how})")
    return _found_file(folder, found[0]) if found else None


def open_trial(folder: str | Path) -> TrialFolder:
    """Find and validate a trial folder's files; raise :class:`InputError` naming what is missing."""
    folder = Path(folder)
    if not folder.is_dir():
        raise InputError(folder, None, "trial folder not found")
    subject_path = folder / "subject.yaml"
    if subject_path.is_file():
        subject = load_subject(subject_path)
        vsk_path = _named_file(folder, subject.vsk, "vsk") or _only_vsk(folder, True)
        if vsk_path is not None:
            name = subject.vsk or vsk_path.name
            subject = with_measurements(subject, read_vsk(vsk_path), name)
    else:
        vsk_path = _only_vsk(folder, False)
        if vsk_path is None:
            load_subject(subject_path)  # the error: neither subject.yaml nor a .vsk
        subject, subject_path = subject_from_vsk(read_vsk(vsk_path), vsk_path.name), vsk_path
    forces = None
    trial = _named_file(folder, subject.trial, "trial")
    if trial is None and (folder / "trial.c3d").is_file():
        trial = _found_file(folder, folder / "trial.c3d")
    elif trial is None and (folder / "markers.csv").is_file():
        trial = _found_file(folder, folder / "markers.csv")
        forces = _found_file(folder, folder / "forces.csv" if (folder / "forces.csv").is_file() else None)
    elif trial is None:
        raise InputError(folder / "trial.c3d", None, "file not found (expected trial.c3d, markers.csv, "
                                                     "or `trial:` in subject.yaml)")
    static = _named_file(folder, subject.static, "static")
    if static is None and (folder / "static.c3d").is_file():
        static = _found_file(folder, folder / "static.c3d")
    return TrialFolder(folder=folder, subject_path=subject_path, subject=subject,
                       trial_path=trial, forces_path=forces, static_path=static, vsk_path=vsk_path)


def sha256(path: str | Path) -> str:
    """SHA-256 of a file's bytes (provenance in HDF5 attributes)."""
    digest = hashlib.sha256()
    try:
        with open(path, "rb") as fh:
            for block in iter(lambda: fh.read(1 << 20), b""):
                digest.update(block)
    except OSError as exc:  # the first read of every input file: permission denied, an I/O error
        raise InputError(path, None, f"cannot be read ({exc.strerror})") from None
    return digest.hexdigest()
