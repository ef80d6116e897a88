"""Trial and session folders: discovery of the files.

A trial folder holds ``trial.c3d`` (or the file ``subject.yaml`` names under
``trial:``, or ``markers.csv`` + ``forces.csv``), an optional ``static.c3d``,
``subject.yaml`` and optionally the lab's Vicon subject file (one ``.vsk``, or the
one ``subject.yaml`` names under ``vsk:``); the subject's schema is
:mod:`gaitcli.kinematics.subject`.

A session folder holds the subject (``subject.yaml`` or a ``.vsk``), a static and
any number of walks, named as the lab names them (``Static 01.c3d``,
``Walking 01.c3d`` …): the walks are the C3Ds ``trials:`` matches (globs), by
default every C3D but the static; the static is the file ``static:`` names or
matches, by default ``static.c3d`` or the one C3D whose name says "static". A
walk is a trial of its own (:func:`open_trial` of its C3D), whose outputs go to
``gait_out/<walk>/``. Nothing in either folder is ever modified.
"""

from __future__ import annotations

import hashlib
import re
from dataclasses import dataclass
from pathlib import Path

from gaitcli.errors import InputError, shown
from gaitcli.io.vsk import read_vsk
from gaitcli.io.yamlfile import read_yaml
from gaitcli.kinematics.subject import Subject, load_subject, subject_from_dict, subject_from_vsk, with_measurements


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
    walk: bool = False  # one walk of a session folder (trial_path), not a trial folder
    emg_mvc_path: Path | None = None  # the MVC trial subject.yaml names (emg_mvc)

    @property
    def name(self) -> str:
        """The trial folder's name, or the walk's file name without its extension."""
        return self.trial_path.stem if self.walk else self.folder.resolve().name

    @property
    def ref(self) -> Path:
        """What names this trial to :func:`open_trial`: the folder, or the walk's C3D."""
        return self.trial_path if self.walk else self.folder

    @property
    def title(self) -> str:
        """The figures' title: the folder's name, and the walk's."""
        folder = self.folder.resolve().name
        return f"{folder} / {self.name}" if self.walk else folder

    @property
    def out_root(self) -> Path:
        """Where the stages write by default: ``gait_out/``, a walk's ``gait_out/<walk>/``."""
        return output_root(self.ref)

    def input_files(self) -> list[Path]:
        paths = (self.subject_path, self.trial_path, self.forces_path, self.static_path, self.vsk_path,
                 self.emg_mvc_path)
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


def _names(paths: list[Path], shown_at_most: int = 4) -> str:
    """The first few file names, quoted, for a message."""
    return ", ".join(shown(p.name) for p in paths[:shown_at_most]) + (", …" if len(paths) > shown_at_most else "")


def _vsk_files(folder: Path) -> list[Path]:
    """The Vicon subject files (``*.vsk``, any case; hidden files not) directly in ``folder``, sorted."""
    return sorted(p for p in folder.iterdir() if p.suffix.lower() == ".vsk" and not p.name.startswith(".")
                  and p.is_file())


def holds_subject(names: list[str]) -> bool:
    """Whether a folder whose file names are ``names`` is a trial or session folder: a ``subject.yaml``, or
    C3D files beside a Vicon subject file (how Nexus leaves a session)."""
    visible = [n.lower() for n in names if not n.startswith(".")]
    return "subject.yaml" in names or (any(n.endswith(".vsk") for n in visible)
                                       and any(n.endswith(".c3d") for n in visible))


def subject_vsk(folder: Path) -> Path | None:
    """The .vsk a folder's subject comes from when it has no subject.yaml and one .vsk (else None)."""
    if (folder / "subject.yaml").is_file():
        return None
    found = _vsk_files(folder)
    return found[0] if len(found) == 1 else None


def _only_vsk(folder: Path, has_yaml: bool) -> Path | None:
    """The folder's one .vsk (None without); more than one is an error naming them."""
    found = _vsk_files(folder)
    if len(found) > 1:
        how = "`vsk:` in subject.yaml naming one" if has_yaml else "a subject.yaml naming one under `vsk:`"
        raise InputError(folder, "vsk", f"{len(found)} Vicon subject files: {_names(found)} (expected one, or "
                                        f"{how})")
    return _found_file(folder, found[0]) if found else None


#: characters that make a name in subject.yaml a glob
GLOB_CHARS = frozenset("*?[")
#: where a session's own outputs go, beside its walks' (gait_out/<walk>/)
SESSION_OUTPUT = "session"


def output_root(ref: Path) -> Path:
    """The default output root of a trial named by ``ref``: ``FOLDER/gait_out``, or for a walk's C3D
    ``SESSION/gait_out/<walk>``."""
    ref = Path(ref)
    return ref.parent / "gait_out" / ref.stem if is_walk(ref) else ref / "gait_out"


def is_walk(ref: Path) -> bool:
    """Whether ``ref`` names one walk of a session (a C3D file) rather than a trial folder."""
    return Path(ref).suffix.lower() == ".c3d" and not Path(ref).is_dir()


def _natural(path: Path) -> list:
    """Sort key: "Walking 2" before "Walking 10"."""
    return [int(part) if part.isdigit() else part.lower() for part in re.split(r"(\d+)", path.name)]


def _c3d_files(folder: Path) -> list[Path]:
    """The C3D files directly in ``folder`` (any case; hidden files not), in natural order."""
    return sorted((p for p in folder.iterdir() if p.suffix.lower() == ".c3d" and not p.name.startswith(".")
                   and p.is_file()), key=_natural)


def _says_static(path: Path) -> bool:
    return "static" in path.stem.lower()


def _matches(folder: Path, pattern: str, key: str) -> list[Path]:
    """The files ``pattern`` (a glob relative to ``folder``) matches inside ``folder``, in natural order."""
    subject = folder / "subject.yaml"
    if "\0" in pattern or Path(pattern).is_absolute() or ".." in Path(pattern).parts:
        raise InputError(subject, key, f"got {shown(pattern)} (expected a file name or glob inside the folder)")
    found = sorted((p for p in folder.glob(pattern) if p.is_file() and not p.name.startswith(".")), key=_natural)
    return [_found_file(folder, p) for p in found]


def session_static(folder: Path, subject: Subject) -> Path | None:
    """A session's static: the file ``static:`` names or matches (one), else ``static.c3d``, else the one C3D
    whose name says "static" (None: no static)."""
    name = subject.static
    if name and GLOB_CHARS & set(name):
        found = _matches(folder, name, "static")
        if len(found) != 1:
            listed = f": {_names(found)}" if found else ""
            raise InputError(folder / "subject.yaml", "static", f"{shown(name)} matches {len(found)} files{listed} "
                                                                "(expected one)")
        return found[0]
    named = _named_file(folder, name, "static")
    if named is not None:
        return named
    if (folder / "static.c3d").is_file():
        return _found_file(folder, folder / "static.c3d")
    statics = [p for p in _c3d_files(folder) if _says_static(p)]
    if len(statics) > 1:
        raise InputError(folder, "static", f"{len(statics)} static trials: {_names(statics)} (expected one, or "
                                           "`static:` in subject.yaml naming one)")
    return _found_file(folder, statics[0]) if statics else None


def session_walks(folder: str | Path, subject: Subject | None = None) -> list[Path] | None:
    """The walks of a session folder, in natural order (possibly none); None for a trial folder (``trial.c3d``,
    ``markers.csv`` or ``trial:`` in subject.yaml, and no ``trials:``). ``subject``: the folder's, if read."""
    folder = Path(folder)
    subject = subject or _subject(folder)[0]
    if not subject.trials and (subject.trial or (folder / "trial.c3d").is_file()
                               or (folder / "markers.csv").is_file()):
        return None
    static = session_static(folder, subject)
    if subject.trials:
        walks: dict[Path, None] = {}
        for pattern in subject.trials:
            found = _matches(folder, pattern, "trials")
            if not found:
                raise InputError(folder / "subject.yaml", "trials", f"{shown(pattern)} matches no file in {folder}")
            walks.update(dict.fromkeys(p for p in found if p != static))
        return list(walks)
    return [p for p in _c3d_files(folder) if p != static and not _says_static(p)]


def _subject(folder: Path) -> tuple[Subject, Path, Path | None]:
    """The folder's subject, the file it came from (subject.yaml, or the .vsk without one) and its .vsk."""
    if not folder.is_dir():
        raise InputError(folder, None, "trial folder not found")
    subject_path = folder / "subject.yaml"
    if subject_path.is_file():
        data = read_yaml(subject_path)
        named = data.get("vsk") if isinstance(data, dict) else None
        vsk_path = _named_file(folder, named, "vsk") or _only_vsk(folder, True)
        if vsk_path is None:
            return subject_from_dict(data, subject_path), subject_path, None
        vsk, name = read_vsk(vsk_path), named or vsk_path.name
        subject = with_measurements(subject_from_dict(data, subject_path, vsk, name), vsk, name)
        return subject, subject_path, vsk_path
    vsk_path = _only_vsk(folder, False)
    if vsk_path is None:
        load_subject(subject_path)  # the error: neither subject.yaml nor a .vsk
    return subject_from_vsk(read_vsk(vsk_path), vsk_path.name), vsk_path, vsk_path


def open_walk(path: str | Path) -> TrialFolder:
    """One walk of a session folder, named by its C3D: the session's subject and static."""
    path = Path(path)
    if not path.is_file():
        raise InputError(path, None, "file not found (expected a walk's C3D in a session folder)")
    folder = path.parent
    subject, subject_path, vsk_path = _subject(folder)
    walk = _found_file(folder, path)
    if walk.stem == SESSION_OUTPUT:
        raise InputError(walk, None, f"a walk may not be named {SESSION_OUTPUT!r}: gait_out/{SESSION_OUTPUT}/ holds "
                                     "the session's own outputs (rename the file)")
    return TrialFolder(folder=folder, subject_path=subject_path, subject=subject, trial_path=walk,
                       static_path=session_static(folder, subject), vsk_path=vsk_path, walk=True,
                       emg_mvc_path=_named_file(folder, subject.emg_mvc, "emg_mvc"))


def open_trial(folder: str | Path) -> TrialFolder:
    """Find and validate a trial's files: a trial folder's, or a walk's (its C3D, :func:`open_walk`); a session
    folder of one walk is that walk. Raise :class:`InputError` naming what is missing."""
    folder = Path(folder)
    if is_walk(folder):
        return open_walk(folder)
    subject, subject_path, vsk_path = _subject(folder)
    walks = session_walks(folder, subject)
    if walks is not None and len(walks) == 1:
        return open_walk(walks[0])
    if walks:
        raise InputError(folder, None, f"a session of {len(walks)} walks ({shown(walks[0].name)} …): `gait run "
                                       f"{folder}` runs every walk; a command runs one walk named by its file, e.g. "
                                       f"{shown(str(walks[0]))}")
    forces = None
    trial = _named_file(folder, subject.trial, "trial")
    if trial is None and (folder / "trial.c3d").is_file():
        trial = _found_file(folder, folder / "trial.c3d")
    elif trial is None and (folder / "markers.csv").is_file():
        trial = _found_file(folder, folder / "markers.csv")
        forces = _found_file(folder, folder / "forces.csv" if (folder / "forces.csv").is_file() else None)
    elif trial is None:
        raise InputError(folder / "trial.c3d", None, "file not found (expected trial.c3d, markers.csv, "
                                                     "`trial:` in subject.yaml, or the walks of a session)")
    static = _named_file(folder, subject.static, "static")
    if static is None and (folder / "static.c3d").is_file():
        static = _found_file(folder, folder / "static.c3d")
    return TrialFolder(folder=folder, subject_path=subject_path, subject=subject,
                       trial_path=trial, forces_path=forces, static_path=static, vsk_path=vsk_path,
                       emg_mvc_path=_named_file(folder, subject.emg_mvc, "emg_mvc"))


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
