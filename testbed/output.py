"""Output files named on the command line: checked before any work, written atomically.

A long run should not end in "No such file or directory" for its last file: commands
check every output file they are given before they start (:func:`check_output_file`),
and figures are drawn to memory and written through a temporary file beside the target
(:func:`save_figure`), so an interrupted run leaves no truncated PNG.
"""

from __future__ import annotations

import contextlib
import io
import os
from collections.abc import Iterator
from pathlib import Path

from pipeline.files import write_atomic


def check_output_file(option: str, path: str | os.PathLike, suffix: str | None = None) -> Path:
    """``path`` as a Path, or a one-line ValueError naming ``option``: a file name (with
    ``suffix``, e.g. ``".png"``, any case, when given) that is not a folder, a device or a
    pipe (the file is replaced, not written into), not inside an episode of a dataset
    (:func:`check_outside_episodes`), in a folder that exists or can be made and where a
    file can be created. Missing folders are made to find out (a dangling link, ``/proc``)
    and removed again: the command may still stop on another argument, and the file is
    written at the end.

    >>> import tempfile
    >>> top = tempfile.mkdtemp()
    >>> check_output_file("--plot", f"{top}/new/fig.png", ".png").name, os.listdir(top)
    ('fig.png', [])
    >>> os.rmdir(top)
    """
    text = os.fspath(path)
    if not text or text.endswith(("/", os.sep)):
        raise ValueError(f"{option}: expected a file name, got {text!r}")
    p = Path(path)
    if suffix is not None and p.suffix.lower() != suffix:
        raise ValueError(f"{option}: expected a {suffix} file name, got {text!r}")
    if p.is_dir():
        raise ValueError(f"{option}: {p} is a folder; expected a file name")
    if p.exists() and not p.is_file():      # /dev/null: replacing it would break the machine
        raise ValueError(f"{option}: {p} exists and is not a regular file (a device, pipe or socket); "
                         "give a file name")
    check_outside_episodes(option, p)
    check_outside_dataset(option, p)
    if p.parent.exists() and not p.parent.is_dir():
        raise ValueError(f"{option}: cannot write to {p.parent} (not a folder)")
    with made_folder(option, p.parent, keep=False):
        check_writable(option, p.parent)
    return p


def _exists(path: Path) -> bool:
    """Whether ``path`` exists; a path that cannot be looked at (no permission) counts as
    existing: it is not one of ours to remove."""
    try:
        return path.exists()
    except OSError:
        return True


@contextlib.contextmanager
def made_folder(option: str, folder: str | os.PathLike, keep: bool = True) -> Iterator[Path]:
    """Make ``folder`` and the folders above it that are missing, for the ``with`` block.

    A folder that cannot be made is a one-line ValueError naming ``option``. The folders
    made here are removed again, deepest first and only while empty, when the block fails
    (any exception, Ctrl-C included) or, without ``keep``, when it ends: a command that
    stops leaves no empty folders behind.

    >>> import tempfile
    >>> top = Path(tempfile.mkdtemp())
    >>> with made_folder("OUT", top / "a" / "b", keep=False) as f:
    ...     f.is_dir()
    True
    >>> os.listdir(top)
    []
    >>> top.rmdir()
    """
    folder = Path(folder)
    made = [f for f in (folder, *folder.parents) if not _exists(f)]      # deepest first
    done = False
    try:
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as exc:
            raise ValueError(f"{option}: cannot make the folder {folder} ({exc.strerror or exc})") from None
        yield folder
        done = keep
    finally:
        if not done:
            for f in made:
                with contextlib.suppress(OSError):      # not empty: something else is in it now
                    f.rmdir()


#: Prefix of the files :func:`check_writable` (and the dataset writer) create and remove
#: (a killed run may leave one: not content).
PROBE = ".camtask-probe."


def check_writable(option: str, folder: str | os.PathLike) -> None:
    """Refuse, naming ``option``, an existing ``folder`` where no file can be created: a
    file is made there and removed (``os.access`` says yes to root, even in /proc)."""
    probe = Path(folder) / f"{PROBE}write-test.{os.getpid()}"
    try:
        os.close(os.open(probe, os.O_WRONLY | os.O_CREAT | os.O_TRUNC, 0o600))   # a stale one of ours: reused
        probe.unlink()
    except OSError as exc:
        raise ValueError(f"{option}: cannot write to {folder} ({exc.strerror or exc})") from None


def episode_of(path: str | os.PathLike, itself: bool = False) -> Path | None:
    """The episode of a dataset (a folder ``episode_*`` beside a manifest.json) that
    ``path`` lies in (or, with ``itself``, is), resolved; None when there is none."""
    from testbed.generate import MANIFEST

    real = Path(path).resolve()
    for folder in ((real,) if itself else ()) + tuple(real.parents):
        if folder.name.startswith("episode_") and (folder.parent / MANIFEST).is_file():
            return folder
    return None


def check_outside_dataset(option: str, path) -> None:
    """Refuse ``path`` in the top folder of a dataset written by ``camtask render`` (beside
    its manifest.json), in one line naming ``option``: there it could replace manifest.json
    or run_info.json, or take an episode's name. (Inside an episode,
    :func:`check_outside_episodes` refuses it.)"""
    from testbed.generate import MANIFEST, read_manifest

    folder = Path(path).resolve().parent
    if not (folder / MANIFEST).is_file():
        return
    try:
        ours = read_manifest(folder) is not None
    except ValueError:                      # not a camtask manifest, or a damaged one beside episodes
        ours = any(p.is_dir() for p in folder.glob("episode_*"))
    if ours:
        raise ValueError(f"{option}: {path} is in the dataset {folder}, beside its {MANIFEST} (which `camtask "
                         "verify` and `camtask render --resume` read); choose a folder outside that dataset")


def check_outside_episodes(option: str, out: str | os.PathLike) -> None:
    """Refuse an ``out`` inside an episode of any dataset: its manifest checksums the
    episode's files, so they would fail `camtask verify` and `--resume` would delete them."""
    folder = episode_of(out)
    if folder is not None:
        raise ValueError(f"{option}: {out} is inside {folder}, an episode of the dataset {folder.parent}, whose "
                         "manifest.json checksums its files; choose a folder outside that dataset")


def count_axis(axis) -> None:
    """Tick a matplotlib axis of counts (cameras, objects, trials) in whole numbers, also
    where one value is drawn (MaxNLocator's integer=True alone then fell back to 3.80,
    3.85, ... 4.20)."""
    import matplotlib.ticker

    axis.set_major_locator(matplotlib.ticker.MaxNLocator(integer=True, min_n_ticks=1))


def save_figure(fig, path: str | os.PathLike, dpi: float = 80) -> None:
    """Draw matplotlib figure ``fig`` as a PNG to ``path`` (its folder made when missing),
    atomically, and close the figure."""
    write_atomic(path, figure_png(fig, dpi))          # makes the folder when missing


def figure_png(fig, dpi: float = 80) -> bytes:
    """Matplotlib figure ``fig`` drawn as PNG bytes in memory; the figure is closed."""
    import matplotlib.pyplot as plt

    png = io.BytesIO()
    try:
        fig.savefig(png, format="png", dpi=dpi)
    finally:
        plt.close(fig)
    return png.getvalue()
