"""Atomic writes: nothing is ever half-written, and a set of files is replaced as a whole.

Temporary files and directories are named ``.NAME.<pid>.<random>.tmp`` beside their target. A
process killed while writing (SIGKILL, power loss) leaves one behind; the next write to the same
target removes those whose process is gone.
"""

from __future__ import annotations

import os
import shutil
import tempfile
import time
from collections.abc import Mapping
from pathlib import Path

from .errors import ThermerrError

#: Leftovers without a readable process id (older releases) are removed after this many seconds.
_STALE_AFTER_S = 3600.0


def _alive(pid: int) -> bool:
    if pid == os.getpid():
        return True
    try:
        os.kill(pid, 0)
    except ProcessLookupError:
        return False
    except PermissionError:  # someone else's live process
        return True
    return True


def _remove_stale(parent: Path, name: str) -> None:
    """Remove ``.NAME.*.tmp`` leftovers of writes to ``parent/NAME`` whose writer is gone."""
    prefix = f".{name}."
    try:
        entries = list(os.scandir(parent))
    except OSError:
        return
    for entry in entries:
        if not (entry.name.startswith(prefix) and entry.name.endswith(".tmp")):
            continue
        middle = entry.name[len(prefix):-len(".tmp")]
        pid_text = middle.split(".", 1)[0]
        try:
            stale = not _alive(int(pid_text))
        except ValueError:
            try:
                stale = time.time() - entry.stat(follow_symlinks=False).st_mtime > _STALE_AFTER_S
            except OSError:
                continue
        if not stale:
            continue
        try:
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path, ignore_errors=True)
            else:
                os.unlink(entry.path)
        except OSError:
            pass


def _fsync_dir(path: Path) -> None:
    try:
        fd = os.open(path, os.O_RDONLY)
    except OSError:
        return
    try:
        os.fsync(fd)
    except OSError:
        pass
    finally:
        os.close(fd)


def _write_file(path: Path, data: str | bytes, mode: int) -> None:
    fd = os.open(path, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o600)
    try:
        os.fchmod(fd, mode)
        raw = data.encode("utf-8") if isinstance(data, str) else data
        view = memoryview(raw)
        while view:
            n = os.write(fd, view)
            view = view[n:]
        os.fsync(fd)
    finally:
        os.close(fd)


def _umask() -> int:
    umask = os.umask(0)
    os.umask(umask)
    return umask


def _file_mode() -> int:
    return 0o666 & ~_umask()


def _parent(target: Path) -> Path:
    return target.parent if str(target.parent) else Path(".")


def _naming(e: OSError, target: Path) -> OSError:
    """``e`` with the output's name when it has none (a full disk fails a write, not an open,
    and ``os.write`` names no file): the one line the user reads says which output failed."""
    if e.filename is None and e.errno is not None:
        named = OSError(e.errno, e.strerror, str(target))
        named.__cause__ = e
        return named
    return e


def write_atomic(path: str | os.PathLike[str], data: str | bytes) -> Path:
    """Write ``data`` to a temporary file beside ``path``, then rename it into place."""
    target = Path(path)
    parent = _parent(target)
    parent.mkdir(parents=True, exist_ok=True)
    _remove_stale(parent, target.name)
    fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp", dir=parent)
    os.close(fd)
    try:
        os.unlink(tmp)
        _write_file(Path(tmp), data, _file_mode())
        os.replace(tmp, target)
    except BaseException as e:
        try:
            os.unlink(tmp)
        except FileNotFoundError:
            pass
        if isinstance(e, OSError):
            raise _naming(e, target) from e
        raise
    return target


def write_set(out_dir: str | os.PathLike[str], files: Mapping[str, str | bytes]) -> Path:
    """Write ``files`` (name → content) as the directory ``out_dir``, all or nothing.

    The files go into a temporary directory beside ``out_dir``, which is then renamed into place.
    A previous ``out_dir`` is replaced only if it holds nothing but files of the same set (a
    previous output of the same command); any other content makes this refuse, so pointing the
    output at a directory of the user's loses nothing. Whatever happens — an error, a full disk,
    Ctrl-C — ``out_dir`` holds either the whole previous set or the whole new one, never a mix.
    """
    target = Path(out_dir)
    parent = _parent(target)
    if target.exists():
        if not target.is_dir():
            raise ThermerrError(f"{target}: exists and is not a directory")
        foreign = sorted(p.name for p in target.iterdir() if p.name not in files)
        if foreign:
            shown = ", ".join(foreign[:5]) + (" ..." if len(foreign) > 5 else "")
            raise ThermerrError(
                f"{target}: exists and holds files this command did not write ({shown}); "
                "choose a new or empty directory")
    parent.mkdir(parents=True, exist_ok=True)
    _remove_stale(parent, target.name)
    tmp = Path(tempfile.mkdtemp(prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp", dir=parent))
    old: Path | None = None
    try:
        mode = _file_mode()
        os.chmod(tmp, 0o777 & ~_umask())  # mkdtemp makes it 0700; an output gets the usual mode
        for name, data in files.items():
            _write_file(tmp / name, data, mode)
        _fsync_dir(tmp)
        if target.exists():
            old = Path(tempfile.mkdtemp(prefix=f".{target.name}.{os.getpid()}.", suffix=".tmp", dir=parent))
            os.rmdir(old)
            os.rename(target, old)
        os.rename(tmp, target)
        _fsync_dir(parent)
    except BaseException as e:
        if old is not None and not target.exists():
            os.rename(old, target)  # put the previous set back
            old = None
        shutil.rmtree(tmp, ignore_errors=True)
        if isinstance(e, OSError):
            raise _naming(e, target) from e
        raise
    finally:
        if old is not None:
            shutil.rmtree(old, ignore_errors=True)
    return target
