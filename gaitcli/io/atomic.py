"""Atomic output: write to a temporary file or folder beside the target, then rename.

An interrupted or failed run never leaves a half-written file that looks valid. Temporary names carry the
writing process's id (``.<target>.<pid>.<random>.part``), so that the next run can remove what a killed run
(SIGKILL, power cut) left behind without touching a concurrent run's work (:func:`remove_stale`).
"""

from __future__ import annotations

import errno
import hashlib
import json
import os
import re
import shutil
import tempfile
import time
import warnings
from contextlib import contextmanager
from pathlib import Path

from gaitcli.errors import GaitWarning, InputError


def _prefix(target: Path) -> str:
    return f".{target.name}.{os.getpid()}."


def _alive(pid: int) -> bool:
    if os.name == "nt":  # os.kill(pid, 0) would send Ctrl-C there: keep the leftovers
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # another user's process
        return True
    return True


def remove_stale(target: str | Path) -> None:
    """Remove temporary files and folders of ``target`` left by runs whose process no longer exists."""
    target = Path(target)
    if not target.parent.is_dir():
        return
    pattern = re.compile(rf"^\.{re.escape(target.name)}\.(?:old-\.{re.escape(target.name)}\.)?(\d+)\..*\.part$")
    for sibling in target.parent.iterdir():
        match = pattern.match(sibling.name)
        if match and not _alive(int(match.group(1))):
            if sibling.is_dir() and not sibling.is_symlink():
                shutil.rmtree(sibling, ignore_errors=True)
            else:
                sibling.unlink(missing_ok=True)


def usual_permissions(path: Path, *, folder: bool) -> None:
    """Mode 0666 (files) or 0777 (folders) less the umask: mkstemp and mkdtemp make 0600 and 0700."""
    umask = os.umask(0)
    os.umask(umask)
    os.chmod(path, (0o777 if folder else 0o666) & ~umask)


#: errors of writing an output that are the machine's or the user's, not gaitcli's: a full disk or quota, a
#: read-only file system, a file too large (exit 2 naming the output; the earlier results stay in place)
WRITE_ERRNOS = (errno.ENOSPC, errno.EDQUOT, errno.EROFS, errno.EFBIG, errno.ENAMETOOLONG, errno.EACCES, errno.EPERM)


def make_parent(target: Path) -> None:
    """Create ``target``'s folder; a file in the way or a folder that cannot be written is an InputError."""
    _check_length(target)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
    except (FileExistsError, NotADirectoryError):  # a file (or /dev/null) where a folder should be
        blocking = next((p for p in reversed(target.parents) if p.exists() and not p.is_dir()), target.parent)
        raise InputError(blocking, None, "is a file (expected an output folder)") from None
    except PermissionError:
        raise InputError(target.parent, None, "cannot be created (permission denied)") from None
    except OSError as exc:  # a name too long, a path under /proc, a read-only file system
        raise InputError(target.parent, None, f"cannot be created ({exc.strerror}; expected an output folder)") \
            from None
    if not os.access(target.parent, os.W_OK | os.X_OK):
        raise InputError(target.parent, None, "is not writable (expected an output folder you can write)")


def _check_length(target: Path) -> None:
    """Refuse a path the system would refuse only after creating its first folders (PATH_MAX, NAME_MAX)."""
    try:
        path_max, name_max = os.pathconf("/", "PC_PATH_MAX"), os.pathconf("/", "PC_NAME_MAX")
    except (OSError, ValueError, AttributeError):  # no pathconf (Windows)
        return
    long_name = next((part for part in target.parts if len(os.fsencode(part)) > name_max), None)
    if long_name is not None:
        named = target if long_name == target.name else target.parent
        raise InputError(named, None, f"a name of {len(os.fsencode(long_name))} bytes is too long "
                                      f"(expected at most {name_max})")
    extra = len(_prefix(target)) - len(target.name) + len("12345678.part")  # mkstemp's 8 letters
    if len(os.fsencode(target.name)) + extra > name_max:  # the temporary name it is written under first
        raise InputError(target, None, f"a name of {len(os.fsencode(target.name))} bytes is too long "
                                       f"(expected at most {name_max - extra}, for its temporary name)")
    length = len(os.fsencode(os.path.abspath(target))) + 40  # the temporary name's suffix
    if length >= path_max:
        raise InputError(target.parent, None, f"the path is too long ({length} bytes with the file name; "
                                              f"expected less than {path_max})")


def check_output_folder(folder: str | Path) -> None:
    """Before any work, leaving nothing behind: ``folder`` can be created and written, as far as can be told
    (the first folder of it that exists is a folder in which a folder can be made; no name or path too long)."""
    folder = Path(os.path.abspath(folder))
    _check_length(folder / "summary.json")
    existing = next(p for p in (folder, *folder.parents) if os.path.lexists(p))
    if not existing.is_dir():
        raise InputError(existing, None, "is a file (expected an output folder)")
    if not os.access(existing, os.W_OK | os.X_OK):
        raise InputError(existing, None, "is not writable (expected an output folder you can write)")
    try:  # the permission bits do not tell for root, /proc or /sys, or a read-only mount: try it
        os.rmdir(tempfile.mkdtemp(prefix=".gait-probe-", dir=existing))
    except OSError as exc:
        first = next((p for p in (folder, *folder.parents) if p.parent == existing), folder)
        raise InputError(first, None, f"cannot be created ({exc.strerror}; expected an output folder you can "
                                       f"write)") from None


def check_output_file(target: str | Path) -> None:
    """Before any work, leaving nothing behind: the file ``target`` (and its temporary name) can be written
    in its folder, as far as can be told (:func:`check_output_folder`)."""
    target = Path(os.path.abspath(target))
    _check_length(target)
    if target.exists() and not target.is_file():
        raise InputError(target, None, "is a folder or other non-file (expected a file gait writes there: move "
                                       "it aside)")
    check_output_folder(target.parent)


@contextmanager
def write_errors(target: Path):
    """Make an OSError of writing ``target`` (:data:`WRITE_ERRNOS`) an InputError naming it."""
    try:
        yield
    except OSError as exc:
        if exc.errno not in WRITE_ERRNOS:
            raise
        raise InputError(target, None, f"cannot be written ({exc.strerror}); nothing was replaced") from None


@contextmanager
def atomic_path(target: str | Path):
    """Yield a temporary path in the target's folder; on success rename it onto ``target``.

    On an exception the temporary file is removed and ``target`` is untouched.
    """
    target = Path(target)
    make_parent(target)
    remove_stale(target)
    with write_errors(target):
        fd, tmp = tempfile.mkstemp(prefix=_prefix(target), suffix=".part", dir=target.parent)
    os.close(fd)
    tmp = Path(tmp)
    try:
        with write_errors(target):
            yield tmp
            usual_permissions(tmp, folder=False)
            os.replace(tmp, target)
    finally:
        if tmp.exists():
            tmp.unlink()


#: the files gait wrote into a folder with the SHA-256 of each (JSON: POSIX path relative to the folder → hex
#: digest), written with the folder by :func:`atomic_folder`; hidden, so that ``gait compare`` and the regression
#: baselines pass it by
MANIFEST = ".gait_files"

#: a manifest larger than this is not gait's (a stage folder lists a few dozen files)
MANIFEST_MAX_BYTES = 1 << 20


def _tree_files(folder: Path) -> list[str]:
    """The relative POSIX paths of every file below ``folder`` but the manifest, sorted."""
    out = []
    for top, _, files in os.walk(folder):
        for name in files:
            rel = Path(top, name).relative_to(folder).as_posix()
            if rel != MANIFEST:
                out.append(rel)
    return sorted(out)


def _digest(path: Path) -> str:
    digest = hashlib.sha256()
    with path.open("rb") as f:
        for block in iter(lambda: f.read(1 << 20), b""):
            digest.update(block)
    return digest.hexdigest()


def read_manifest(folder: Path) -> dict[str, str | None] | None:
    """The files gait recorded writing into ``folder``, each with its SHA-256 (None where the manifest gives
    names only, as an older gaitcli wrote it); None without a readable manifest (an older gaitcli's folder, or a
    manifest that is not gait's: a link, too large, not JSON of names)."""
    path = folder / MANIFEST
    if path.is_symlink() or not path.is_file():
        return None
    try:
        if path.stat().st_size > MANIFEST_MAX_BYTES:
            return None
        written = json.loads(path.read_text(encoding="utf-8"))
    except (OSError, ValueError):  # UnicodeDecodeError and JSONDecodeError are ValueErrors
        return None
    if isinstance(written, list) and all(isinstance(n, str) for n in written):
        return dict.fromkeys(written)
    if isinstance(written, dict) and all(isinstance(d, str) for d in written.values()):
        return written
    return None


def check_replaceable(target: str | Path) -> None:
    """Raise :class:`InputError` naming the first file below the folder ``target`` that gait did not write:
    one not in the folder's manifest (:data:`MANIFEST`) or changed since (its SHA-256 differs: the user saved
    their own file under gait's name); and any link. Replacing the folder whole would delete it. A folder
    without a readable manifest (an older gaitcli's, or one whose manifest was deleted) is never deleted:
    :func:`atomic_folder` keeps it whole beside the new one, so nothing in it is refused."""
    target = Path(target)
    if not target.is_dir() or target.is_symlink():
        return
    written = read_manifest(target)
    if written is None:
        return
    for top, folders, files in os.walk(target):
        folders.sort()
        for name in sorted(files) + [f for f in folders if Path(top, f).is_symlink()]:
            path = Path(top, name)
            rel = path.relative_to(target).as_posix()
            ours = (name.startswith(".") and name.endswith(".part")) or rel == MANIFEST  # a leftover, the list
            ours = ours or rel in written
            if path.is_symlink() or not ours:
                raise InputError(path, None, "is not an output of gait, and the run would replace its folder "
                                             "(expected only gait's outputs there: move the file, or choose "
                                             "another -o)")
            if written.get(rel) is not None and _digest(path) != written[rel]:
                raise InputError(path, None, "was changed since gait wrote it, and the run would replace its "
                                             "folder (move the file, or choose another -o)")


def _kept_name(target: Path) -> Path:
    """A free sibling name for a previous folder kept whole: ``<name>.kept-<YYYYmmddTHHMMSS>[-k]``."""
    stamp = time.strftime("%Y%m%dT%H%M%S")
    kept, k = target.with_name(f"{target.name}.kept-{stamp}"), 1
    while kept.exists():
        k += 1
        kept = target.with_name(f"{target.name}.kept-{stamp}-{k}")
    return kept


@contextmanager
def atomic_folder(target: str | Path):
    """Yield a temporary folder; on success it replaces ``target`` (the previous run's outputs) whole.

    A file (not a folder) at ``target``, or a file in it that gait did not write (:func:`check_replaceable`),
    is the user's: an InputError, and nothing is moved. The files written go into the folder's manifest
    (:data:`MANIFEST`) with their digests, so that the next run replaces only those, unchanged. A previous
    folder without a readable manifest, which gait cannot prove it wrote, is kept whole beside the new one as
    ``<name>.kept-<time>`` (warned). Leftovers of killed runs are removed first (:func:`remove_stale`).
    """
    target = Path(target)
    make_parent(target)
    if target.exists() and not target.is_dir():
        raise InputError(target, None, "is a file (expected the output folder; move or rename the file)")
    check_replaceable(target)
    unproven = target.is_dir() and not target.is_symlink() and read_manifest(target) is None and any(target.iterdir())
    remove_stale(target)
    with write_errors(target):
        tmp = Path(tempfile.mkdtemp(prefix=_prefix(target), suffix=".part", dir=target.parent))
    try:
        with write_errors(target):
            yield tmp
            manifest = tmp / MANIFEST
            digests = {rel: _digest(tmp / rel) for rel in _tree_files(tmp)}
            manifest.write_text(json.dumps(digests, indent=0) + "\n", encoding="utf-8")
            usual_permissions(manifest, folder=False)
            usual_permissions(tmp, folder=True)
            old = None
            if target.exists():
                old = target.with_name(f".{target.name}.old-{tmp.name}")
                target.rename(old)
            tmp.rename(target)
        if old is not None and unproven:
            kept = _kept_name(target)
            old.rename(kept)
            warnings.warn(f"{target}: held files without gait's list of its own ({MANIFEST}): kept whole as "
                          f"{kept.name} beside the new outputs (delete it when it holds nothing of yours)",
                          GaitWarning, stacklevel=3)
        elif old is not None:
            shutil.rmtree(old, ignore_errors=True)
    finally:
        if tmp.exists():
            shutil.rmtree(tmp, ignore_errors=True)
