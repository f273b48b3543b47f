"""Files and folders that appear whole: a temporary name beside the target, then a rename.

Both helpers give what a plain ``open`` or ``mkdir`` would: permissions from the process
umask (0644 files, 0755 folders under the usual 022). ``tempfile.mkstemp`` and
``mkdtemp`` make theirs 0600 and 0700, which a rename keeps, so datasets written through
them could not be read by the other users of a shared machine or cluster.
"""

from __future__ import annotations

import contextlib
import errno
import os
import secrets
from collections.abc import Iterable
from pathlib import Path

#: Attempts at an unused random name before giving up (each has 2**48 choices).
ATTEMPTS = 100


def _create(parent: Path, prefix: str, suffix: str, make):
    """``(path, make(path))`` for an unused ``parent/prefix<random>suffix``; ``make`` creates
    the path or raises FileExistsError."""
    for _ in range(ATTEMPTS):
        path = parent / f"{prefix}{secrets.token_hex(6)}{suffix}"
        try:
            return path, make(path)
        except FileExistsError:
            continue
        except BaseException:               # e.g. Ctrl-C once it existed, before the caller had it
            with contextlib.suppress(OSError):
                path.rmdir() if path.is_dir() else path.unlink(missing_ok=True)
            raise
    raise FileExistsError(f"no unused temporary name {prefix}*{suffix} in {parent}")


def temp_folder(parent: str | os.PathLike, prefix: str, suffix: str = ".tmp") -> Path:
    """A new empty folder ``parent/prefix<random>suffix``, permissions as ``mkdir`` gives."""
    return _create(Path(parent), prefix, suffix, Path.mkdir)[0]


def written_file(path: str | os.PathLike) -> Path:
    """The file that writing ``path`` changes: ``path``, or where the symbolic link ``path``
    leads (followed to the end; it may not exist yet), as ``open(path, "w")`` would write.
    A rename onto the link itself would replace the link with a file and leave its target
    as it was. A loop of links is an OSError."""
    path = Path(path)
    if not path.is_symlink():
        return path
    target = Path(os.path.realpath(path))
    if target.is_symlink():                 # realpath stops in a loop
        error = OSError(f"cannot write {path}: {os.strerror(errno.ELOOP)}")
        error.errno = errno.ELOOP
        raise error
    return target


def write_atomic(path: str | os.PathLike, data: bytes | Iterable[bytes]) -> None:
    """Write ``data`` (bytes, or pieces of them in order) to ``path`` through a temporary
    file in the same folder (made when missing) and ``os.replace``. A symbolic link is
    written through: its target is replaced, from a temporary file beside the target
    (:func:`written_file`)."""
    path = Path(path)
    target = written_file(path)
    target.parent.mkdir(parents=True, exist_ok=True)
    tmp, fd = _create(target.parent, f".{target.name}.", ".tmp",
                      lambda p: os.open(p, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666))
    try:
        with os.fdopen(fd, "wb") as fh:
            fh.write(data) if isinstance(data, bytes | bytearray | memoryview) else fh.writelines(data)
        os.replace(tmp, target)
    except OSError as exc:                  # a full disk: say which file, as testbed.png does
        tmp.unlink(missing_ok=True)
        error = OSError(f"cannot write {path}: {exc.strerror or exc}")
        error.errno = exc.errno
        raise error from None
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise
