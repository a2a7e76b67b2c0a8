"""One writer per output, and outputs checked before the work that makes them.

:func:`claim_output` is what every command that writes an artefact runs its work in. It
checks that the output can be written (before anything is computed), creates its
missing folders, and holds an exclusive lock beside it, ``<output>.lock``, for the
whole run: a second posegen on the same output fails at once, naming the pid of the
first. The lock is an ``flock`` on that file, so the kernel releases it when its
holder dies, even by ``kill -9``; the next run takes the file over and says so, and
removes the temporary files the dead run's atomic writes left. On
failure the folders it created are removed again when they are empty: a command that
fails leaves no new file behind.
"""

from __future__ import annotations

import contextlib
import enum
import fcntl
import glob
import logging
import os
import shutil
import tempfile
from collections.abc import Iterator, Sequence
from pathlib import Path

from posegen.errors import OutputError
from posegen.io.arrays import SIDECAR_SUFFIX
from posegen.io.atomic import leftover_temporaries

LOG = logging.getLogger(__name__)

LOCK_SUFFIX = ".lock"
_LOCK_TRIES = 20  # a holder may remove the lock file between our open and our lock: try again


class OutputKind(str, enum.Enum):
    """What an output is."""

    FILE = "file"
    FOLDER = "folder"  # a folder of files (a calibration)


def lock_path(output: str | Path) -> Path:
    """The lock file of an output: ``<output>.lock`` beside it."""
    output = Path(output)
    return output.with_name(output.name + LOCK_SUFFIX)


def _probe(folder: Path) -> None:
    """Check that a file can be created in ``folder`` (a real try: permissions lie to root)."""
    if not folder.is_dir():
        raise OutputError(f"cannot write in {folder}: not a folder")
    try:
        fd, name = tempfile.mkstemp(prefix=".posegen-probe.", dir=folder)
    except OSError as exc:
        raise OutputError(f"cannot write in {folder}: {exc.strerror}") from exc
    os.close(fd)
    os.unlink(name)


def _existing_ancestor(path: Path) -> Path:
    ancestor = path
    while not ancestor.exists() and ancestor != ancestor.parent:
        ancestor = ancestor.parent
    return ancestor


def check_named(path: str | Path) -> None:
    """Check that an output path names a file or folder (not ``""``, ``.``, ``..`` or ``/``).

    Raises:
        OutputError: The path names nothing to write.

    Example:
        >>> check_named("plans/pool.yaml")
        >>> check_named("")
        Traceback (most recent call last):
        posegen.errors.OutputError: '': names no file or folder to write; give a name

    """
    if not str(path).strip() or Path(path).name in ("", ".", ".."):
        raise OutputError(f"'{path}': names no file or folder to write; give a name")


def check_writable(path: str | Path, kind: OutputKind = OutputKind.FILE) -> None:
    """Check, without changing anything, that ``path`` can be written as an output of ``kind``.

    Raises:
        OutputError: The path is a folder where a file is expected (or the reverse), an
            existing special file, a file named like an arrays sidecar (``.npz``), or in a
            place where no file can be created.

    """
    check_named(path)
    path = Path(path)
    if kind is OutputKind.FILE and path.suffix.lower() == SIDECAR_SUFFIX:
        kept = "not overwriting it" if path.exists() else "not writing it"
        raise OutputError(
            f"{path}: a {SIDECAR_SUFFIX} name is kept for the arrays posegen writes beside a header: {kept}; "
            "give another name (e.g. .yaml)"
        )
    if path.exists():
        if kind is OutputKind.FILE and path.is_dir():
            raise OutputError(f"{path} is a folder; give a file name")
        if kind is OutputKind.FILE and not path.is_file():
            raise OutputError(f"{path} exists and is not a regular file")
        if kind is OutputKind.FOLDER and not path.is_dir():
            raise OutputError(f"{path} exists and is not a folder")
    if kind is OutputKind.FOLDER and path.is_dir():
        _probe(path)
    _probe(_existing_ancestor(path.absolute().parent))


def check_replaceable(path: str | Path, marker: str) -> None:
    """Check that a folder output replaced whole is absent, empty, or an artefact of its kind.

    A folder swapped in whole (:func:`posegen.io.atomic.swap_folder`) removes the folder
    it replaces, with every file in it: a folder that does not hold ``marker`` (a
    calibration folder's ``calibration.yaml``) is someone else's, and never replaced.

    Raises:
        OutputError: ``path`` is a non-empty folder without ``marker``.

    """
    path = Path(path)
    if path.is_dir() and not (path / marker).is_file() and any(path.iterdir()):
        raise OutputError(f"{path} is a folder with other files and no {marker}: not replacing it; give a new folder")


def input_files(path: str | Path) -> list[Path]:
    """An input and the files read with it: a header's sidecars (named by hash, or an older ``<stem>.npz``)."""
    path = Path(path)
    found = [path]
    if path.is_file():
        found += [p for p in path.parent.glob(glob.escape(path.name) + ".*.npz") if p.is_file()]
        legacy = path.with_suffix(".npz")
        if legacy != path and legacy.is_file():
            found.append(legacy)
    return found


def _same(first: Path, second: Path) -> bool:
    if first.resolve() == second.resolve():
        return True
    try:
        return os.path.samefile(first, second)  # hard links
    except OSError:
        return False


def _inside(path: Path, folder: Path) -> bool:
    return folder.is_dir() and folder.resolve() in path.resolve().parents


def check_apart(outputs: Sequence[str | Path | None], inputs: Sequence[str | Path | None]) -> None:
    """Check, before any work, that no output is, contains, lies inside or shares a file with an input.

    Inputs count with the files read with them (:func:`input_files`: a header's
    sidecar); an output folder (a calibration, a bag) may not hold an input, and no
    output may be written inside an input folder (a recorded bag). ``None`` entries are
    skipped (an option not given).

    Raises:
        OutputError: An output names nothing (``""``, ``.``) or would overwrite, replace or be
            written into an input.

    """
    for named in outputs:
        if named is not None:
            check_named(named)
    read = [f for i in inputs if i is not None for f in input_files(i)]
    for output in (Path(o) for o in outputs if o is not None):
        for source in read:
            if _same(output, source):
                raise OutputError(f"{output} is an input of this command ({source}): not overwriting it")
            if _inside(output, source):
                raise OutputError(f"{output} is inside the input {source}: not writing into it")
            if _inside(source, output):
                raise OutputError(f"{output} holds the input {source}: not replacing it")


def _read_holder(fd: int) -> str:
    os.lseek(fd, 0, os.SEEK_SET)
    return os.read(fd, 64).decode(errors="replace").strip()


def _is_running(pid: str) -> bool:
    try:
        os.kill(int(pid), 0)
    except (ValueError, ProcessLookupError):
        return False
    except PermissionError:  # another user's process
        return True
    return True


class OutputLock:
    """An exclusive lock on an output, held by this process until :meth:`release`."""

    def __init__(self, output: str | Path) -> None:
        self.output = Path(output)
        self.path = lock_path(self.output)
        self._fd: int | None = None

    def acquire(self) -> None:
        """Take the lock, or fail at once if another process holds it.

        Raises:
            OutputError: Another posegen holds it, or the file system cannot lock.

        """
        for _ in range(_LOCK_TRIES):
            try:
                fd = os.open(self.path, os.O_RDWR | os.O_CREAT | os.O_CLOEXEC, 0o644)
            except OSError as exc:
                raise OutputError(f"cannot create the lock {self.path}: {exc.strerror}") from exc
            try:
                fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            except BlockingIOError:
                holder = _read_holder(fd) or "?"
                os.close(fd)
                raise OutputError(f"{self.output} is being written by another posegen (pid {holder})") from None
            except OSError as exc:
                os.close(fd)
                raise OutputError(f"cannot lock {self.path}: {exc.strerror}") from exc
            try:
                current = os.stat(self.path).st_ino == os.fstat(fd).st_ino
            except FileNotFoundError:
                current = False
            if current:
                break
            os.close(fd)  # we locked a file its holder had just removed
        else:
            raise OutputError(f"cannot lock {self.path}: it keeps being replaced")
        previous = _read_holder(fd)
        if previous:
            state = "no longer holds it" if _is_running(previous) else "is no longer running"
            LOG.warning("taking over the lock of %s left by posegen pid %s, which %s", self.output, previous, state)
        os.ftruncate(fd, 0)
        os.lseek(fd, 0, os.SEEK_SET)
        os.write(fd, f"{os.getpid()}\n".encode())
        self._fd = fd

    def release(self) -> None:
        """Remove the lock file and release the lock."""
        if self._fd is None:
            return
        try:
            if os.stat(self.path).st_ino == os.fstat(self._fd).st_ino:
                os.unlink(self.path)
        except FileNotFoundError:
            pass
        os.close(self._fd)
        self._fd = None

    def __enter__(self) -> OutputLock:
        self.acquire()
        return self

    def __exit__(self, *_: object) -> None:
        self.release()


def _make_parents(folder: Path) -> list[Path]:
    """Create ``folder`` and its missing ancestors; the ones created, outermost first."""
    missing = []
    while not folder.exists():
        missing.append(folder)
        folder = folder.parent
    created: list[Path] = []
    for path in reversed(missing):
        try:
            path.mkdir()
        except FileExistsError:
            continue
        except OSError as exc:
            _remove_empty(created)
            raise OutputError(f"cannot create {path}: {exc.strerror}") from exc
        created.append(path)
    return created


def _remove_empty(folders: Sequence[Path]) -> None:
    for folder in reversed(folders):
        try:
            folder.rmdir()
        except OSError:
            return  # not empty (a checkpoint to resume from, say): keep it and its parents


def _remove_leftovers(path: Path, kind: OutputKind, beside: Sequence[str | Path]) -> None:
    """Remove the temporary files a killed writer of these outputs left (only a lock holder writes them)."""
    leftovers = [p for target in [path, *(Path(b) for b in beside)] for p in leftover_temporaries(target)]
    if kind is OutputKind.FOLDER and path.is_dir():
        leftovers.extend(p for p in path.iterdir() if p.name.startswith(".") and ".tmp" in p.name)
    for leftover in leftovers:
        LOG.info("removing %s, left by a killed run", leftover)
        if leftover.is_dir() and not leftover.is_symlink():
            shutil.rmtree(leftover, ignore_errors=True)  # a bag's scratch folder
        else:
            leftover.unlink(missing_ok=True)


@contextlib.contextmanager
def claim_output(
    path: str | Path, kind: OutputKind = OutputKind.FILE, beside: Sequence[str | Path] = ()
) -> Iterator[OutputLock]:
    """Check an output, create its folders and hold its lock for the block.

    Args:
        path: The output (a file, or a folder of files).
        kind: What the output is.
        beside: Other files written with it (a CSV beside a route, plots); checked too
            and covered by the same lock.

    Raises:
        OutputError: The output cannot be written, or another posegen is writing it.

    """
    path = Path(path)
    check_writable(path, kind)
    for other in beside:
        check_writable(other, OutputKind.FILE)
    created = _make_parents(path.absolute().parent)
    lock = OutputLock(path)
    try:
        lock.acquire()
    except BaseException:
        _remove_empty(created)
        raise
    _remove_leftovers(path, kind, beside)
    try:
        yield lock
    except BaseException:
        lock.release()
        _remove_empty(created)
        raise
    lock.release()
