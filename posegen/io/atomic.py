"""Atomic file writes: an output is either fully there or not changed at all.

Every rename that puts an output in place goes through :func:`rename_into_place`, and
every folder swap through :func:`swap_folder`; both pass a *crash point* before and
after the rename. A crash point does nothing unless the environment variable
``POSEGEN_CRASH_AT`` holds a number N: the process then kills itself (``SIGKILL``, no
clean-up runs) at the Nth crash point it reaches, so a test can stop a real command at
every rename boundary in turn (``tests/robustness/test_kill.py``). When
``POSEGEN_CRASH_LOG`` names a file, each crash point reached appends its label there.
"""

from __future__ import annotations

import contextlib
import ctypes
import errno
import glob
import itertools
import os
import shutil
import signal
import tempfile
from collections.abc import Iterator
from pathlib import Path

CRASH_AT = "POSEGEN_CRASH_AT"  # kill this process at the Nth crash point (tests)
CRASH_LOG = "POSEGEN_CRASH_LOG"  # append the label of every crash point reached to this file (tests)
_REACHED = itertools.count(1)  # crash points reached by this process: the one piece of module state, for tests
_RENAME_EXCHANGE = 2  # linux/fs.h: swap two existing paths atomically


def crash_point(label: str) -> None:
    """A rename boundary: kill the process here if ``POSEGEN_CRASH_AT`` says so (tests only)."""
    wanted = os.environ.get(CRASH_AT)
    log = os.environ.get(CRASH_LOG)
    if wanted is None and log is None:
        return
    reached = next(_REACHED)
    if log:
        with open(log, "a", encoding="utf-8") as handle:
            handle.write(f"{reached} {label}\n")
    if wanted is not None and wanted.strip() == str(reached):
        os.kill(os.getpid(), signal.SIGKILL)


def rename_into_place(source: Path, target: Path) -> None:
    """``os.replace`` with a crash point on each side: the one way an output file lands."""
    crash_point(f"before {target.name}")
    os.replace(source, target)
    crash_point(f"after {target.name}")


def _temporary_prefix(path: Path) -> str:
    return f".{path.name}."


def leftover_temporaries(path: str | Path) -> list[Path]:
    """Temporary files and staging folders of writes to ``path`` that a killed process left beside it."""
    path = Path(path)
    return sorted(path.parent.glob(glob.escape(_temporary_prefix(path)) + "*.tmp*"))


@contextlib.contextmanager
def atomic_path(path: str | Path) -> Iterator[Path]:
    """A temporary path beside ``path`` to write to; renamed onto ``path`` when the block succeeds.

    For writers that want a file name (``savefig``, a zip writer). If the block raises,
    or the process dies in it, ``path`` is unchanged and the temporary file is removed
    (or, after a kill, left as a hidden ``.<name>.*.tmp*`` beside it, which the next
    writer of ``path`` removes: :func:`leftover_temporaries`).
    """
    path = Path(path)
    path.parent.mkdir(parents=True, exist_ok=True)
    fd, name = tempfile.mkstemp(prefix=_temporary_prefix(path), suffix=".tmp" + path.suffix, dir=path.parent)
    os.close(fd)
    tmp = Path(name)
    try:
        yield tmp
        with tmp.open("rb+") as handle:
            os.fsync(handle.fileno())
        os.chmod(tmp, 0o644)  # mkstemp creates 0600; artefacts are ordinary files
        rename_into_place(tmp, path)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def write_atomic(path: str | Path, content: str | bytes) -> None:
    """Write a file (text, or bytes) so that it is either fully there or not changed at all."""
    with atomic_path(path) as tmp:
        tmp.write_bytes(content.encode() if isinstance(content, str) else content)


def _exchange(first: Path, second: Path) -> bool:
    """Swap two existing paths in one step (``renameat2(RENAME_EXCHANGE)``); False where the system cannot."""
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        renameat2 = libc.renameat2
    except (OSError, AttributeError):  # not Linux, or a libc older than glibc 2.28
        return False
    at_cwd = -100  # AT_FDCWD
    result = renameat2(at_cwd, os.fsencode(first), at_cwd, os.fsencode(second), _RENAME_EXCHANGE)
    if result == 0:
        return True
    code = ctypes.get_errno()
    if code in (errno.ENOSYS, errno.EINVAL, errno.ENOTSUP):  # the kernel or the file system cannot exchange
        return False
    raise OSError(code, os.strerror(code), str(first))


def swap_folder(staging: Path, target: Path) -> None:
    """Put the folder ``staging`` at ``target`` in one rename, and remove the folder it replaces.

    With no ``target``, a plain rename. Otherwise ``renameat2(RENAME_EXCHANGE)`` swaps
    the two folders in one step, so a reader (or a kill) sees the old folder or the new
    one, never a mix; the old one, now at ``staging``, is then removed (after a kill, a
    hidden ``.<name>.*.tmp`` that the next writer of ``target`` removes). Where the
    system cannot exchange (not Linux, or a file system without it) the old folder is
    renamed aside first: a kill between the two renames leaves ``target`` absent and the
    old folder hidden beside it, never a mix of two runs.
    """
    crash_point(f"before {target.name}/")
    if not target.exists():
        os.rename(staging, target)
    elif _exchange(staging, target):
        crash_point(f"after {target.name}/ (old not yet removed)")
        shutil.rmtree(staging, ignore_errors=True)
    else:
        aside = Path(tempfile.mkdtemp(prefix=_temporary_prefix(target), suffix=".tmp", dir=target.parent))
        os.rename(target, aside / target.name)
        crash_point(f"between {target.name}/ aside and in place")
        os.rename(staging, target)
        shutil.rmtree(aside, ignore_errors=True)
    crash_point(f"after {target.name}/")


def staging_folder(target: Path) -> Path:
    """A new empty hidden folder beside ``target`` to write a folder artefact into (``.<name>.*.tmp``)."""
    target.parent.mkdir(parents=True, exist_ok=True)
    folder = Path(tempfile.mkdtemp(prefix=_temporary_prefix(target), suffix=".tmp", dir=target.parent))
    os.chmod(folder, 0o755)  # mkdtemp creates 0700; artefacts are ordinary folders
    return folder


@contextlib.contextmanager
def atomic_folder(path: str | Path) -> Iterator[Path]:
    """A staging folder beside ``path`` to write a whole folder into; swapped in when the block succeeds.

    Every file of the folder comes from this block: files of an older folder at ``path``
    are not kept (see :func:`swap_folder`). If the block raises, ``path`` is unchanged
    and the staging folder removed.
    """
    path = Path(path)
    staging = staging_folder(path)
    try:
        yield staging
        swap_folder(staging, path)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
