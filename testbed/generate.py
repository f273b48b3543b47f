"""A dataset of episodes on disk: the manifest, resuming, and spreading episodes over Dask.

::

    DIR/manifest.json          every finished episode: index, name, seed, spawn key, frames,
                               checksum of each of its files (``checksum``: BLAKE3); and
                               the run's arguments
    DIR/run_info.json          wall-clock times, host names, worker count, package versions
                               (the only file that differs between identical runs)
    DIR/episode_NNNN/          one episode (testbed.episodes, docs/dataset.md)

The manifest is written before the first episode (with none listed) and rewritten
atomically (temporary file + os.replace) as episodes finish and at the end of the run
(:class:`ManifestWriter`); it lists episodes
in index order with sorted keys, so two runs with the same arguments give the same
manifest whatever the worker count or completion order.
"""

from __future__ import annotations

import contextlib
import errno
import fcntl
import itertools
import json
import os
import platform
import re
import shutil
import socket
import sys
import threading
import time
from collections.abc import Callable, Iterator
from pathlib import Path

from scene.checks import names
from testbed import stops
from testbed.checksum import ALGORITHM, ALGORITHMS
from testbed.episodes import (
    EpisodeConfig,
    checksums,
    episode_name,
    render_episode,
    without_scene_own,
)
from testbed.output import PROBE  # the files check_out and check_workers_share make and remove
from testbed.parallel import default_workers

MANIFEST = "manifest.json"
RUN_INFO = "run_info.json"
#: Locked (``flock``) by the run writing DIR, deleted when it ends; see :func:`exclusive`.
LOCK = ".camtask-render.lock"
#: 2: BLAKE3 checksums named by ``checksum``; 1: sha256, no ``checksum`` key (still resumable).
FORMAT_VERSION = 2
#: What an episode holds. 3: the sight radii also hold where people become too narrow
#: to be seen, and a tenth person's default colour is lime, not grey; 2: ``scanlines.npz``
#: has the blind radii and ``gt_hull.json`` is carved beyond them; 1 (manifests without
#: ``episode_layout``): before. A run is not resumed across layouts: its episodes would
#: differ in kind, not just in bytes.
EPISODE_LAYOUT = 3


def write_json_atomic(path: Path, data: dict) -> None:
    from pipeline.files import write_atomic

    write_atomic(path, (json.dumps(data, indent=1, sort_keys=True) + "\n").encode())


def read_manifest(out: Path) -> dict | None:
    path = Path(out) / MANIFEST
    if not path.is_file():
        return None
    try:
        m = json.loads(path.read_text())
    except (OSError, ValueError) as exc:
        raise ValueError(f"cannot read {path} ({exc})") from None
    problem = _manifest_shape_problem(m)
    if problem:
        raise ValueError(f"cannot read {path} (not a camtask manifest: {problem})")
    return m


def _manifest_shape_problem(m) -> str | None:
    """What is missing from a parsed manifest for the commands that read it, else None."""
    if not isinstance(m, dict):
        return f"expected a JSON object, got {type(m).__name__ if m is not None else 'null'}"
    if not isinstance(m.get("episodes"), list):
        return "no list of episodes"
    for key, least in (("episodes_planned", 0), ("episode_layout", 1)):
        if key in m and not (_is_int(m[key]) and m[key] >= least):
            return f"{key} is {m[key]!r}, expected an integer >= {least}"
    seen = set()
    for i, e in enumerate(m["episodes"]):
        if not (isinstance(e, dict) and _is_int(e.get("index")) and isinstance(e.get("name"), str)
                and _is_int(e.get("frames")) and isinstance(e.get("files"), dict)):
            return f"episodes[{i}] lacks an integer index and frames, a name or a files mapping"
        if e["index"] < 0:
            return f"episodes[{i}]: index {e['index']}, expected >= 0"
        if e["name"] != episode_name(e["index"]):       # a folder of DIR, never a path elsewhere
            return f"episodes[{i}] is named {e['name']!r}, expected {episode_name(e['index'])!r} for its index"
        if e["index"] in seen:
            return f"episodes[{i}]: index {e['index']} listed twice"
        seen.add(e["index"])
    return None


def _is_int(value) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def manifest(config: EpisodeConfig, episodes: int, entries: dict[int, dict]) -> dict:
    return {"format_version": FORMAT_VERSION, "episode_layout": EPISODE_LAYOUT, "checksum": ALGORITHM,
            "episodes_planned": episodes,
            "config": config.to_dict(), "episodes": [entries[i] for i in sorted(entries)]}


class ManifestWriter:
    """``DIR/manifest.json`` of a run, rewritten atomically as its episodes finish.

    The bytes are those of :func:`write_json_atomic` of :func:`manifest`, but each entry is
    serialised once, when it is added: an entry lists every file of its episode (~14,400
    for 300 frames of 16 cameras, ~1.4 MB of JSON), so serialising the whole manifest after
    every episode grew with the square of the episode count. And after an episode the file
    is rewritten only once the time since the last rewrite is ``PACE`` times what that
    rewrite took: at most ~1/PACE of the run goes to the manifest (for small manifests that
    is after every episode). :meth:`flush` writes whatever is not yet on disk.
    """

    #: Rewrite no sooner than this many times the last rewrite's duration after it.
    PACE = 20.0

    def __init__(self, out: Path, config: EpisodeConfig, episodes: int, entries: dict[int, dict],
                 on_disk: bool = False):
        """entries : the finished episodes so far; on_disk : the file lists them already."""
        self.path = Path(out) / MANIFEST
        head = json.dumps(manifest(config, episodes, {}), indent=1, sort_keys=True) + "\n"
        self.before, self.after = (x.encode() for x in head.split('"episodes": []', 1))
        self.entries = {i: self._entry_bytes(e) for i, e in entries.items()}
        self.unwritten = not on_disk
        self.ready_at = 0.0                       # perf_counter time from which a rewrite is due

    @staticmethod
    def _entry_bytes(entry: dict) -> bytes:
        """``entry`` as it stands in the manifest, two levels deep (keys at 3 spaces)."""
        return json.dumps(entry, indent=1, sort_keys=True).replace("\n", "\n  ").encode()

    def chunks(self) -> list[bytes]:
        """The file's bytes, in pieces (the entries are not copied into one string)."""
        if not self.entries:
            return [self.before, b'"episodes": []', self.after]
        body = [x for i in sorted(self.entries) for x in (b",\n  ", self.entries[i])]
        return [self.before, b'"episodes": [\n  ', *body[1:], b"\n ]", self.after]

    def on_disk(self) -> bool:
        """Whether the file holds these bytes already."""
        try:
            return self.path.read_bytes() == b"".join(self.chunks())
        except OSError:
            return False

    def add(self, entry: dict) -> None:
        """List a finished episode; rewrite the file when it is due."""
        self.entries[int(entry["index"])] = self._entry_bytes(entry)
        self.unwritten = True
        if time.perf_counter() >= self.ready_at:
            self.flush()

    def flush(self) -> None:
        """Write the manifest now if it lists episodes the file does not."""
        if not self.unwritten:
            return
        from pipeline.files import write_atomic

        start = time.perf_counter()
        write_atomic(self.path, self.chunks())
        end = time.perf_counter()
        self.unwritten = False
        self.ready_at = end + self.PACE * (end - start)


def manifest_algorithm(m: dict) -> str:
    """The checksum algorithm of a manifest read from disk (sha256 before format 2)."""
    algorithm = m.get("checksum", "sha256")
    if algorithm not in ALGORITHMS:
        raise ValueError(f"manifest: checksum {algorithm!r}; expected one of {', '.join(ALGORITHMS)}")
    return algorithm


def episode_problems(out: Path, entry: dict, algorithm: str = ALGORITHM) -> dict[str, list[str]]:
    """What differs between ``out/entry['name']`` and its manifest entry.

    Returns {"missing": listed files not on disk, "changed": files whose checksum differs,
    "extra": files on disk not listed, and any other entry but a folder (a FIFO, a link to
    nowhere or to itself: never read)}, each a sorted list of paths relative to the
    episode folder; all empty when the episode is intact. A missing folder has every
    listed file missing.
    """
    folder = Path(out) / entry["name"]
    listed = entry["files"]
    others: list[str] = []                  # a FIFO, a link to nowhere: never read, always extra
    found = checksums(folder, algorithm=algorithm, others=others) if folder.is_dir() else {}
    return {"missing": sorted(set(listed) - set(found)),
            "changed": sorted(k for k in found if k in listed and found[k] != listed[k]),
            "extra": sorted((set(found) - set(listed)) | set(others))}


def problems_text(problems: dict[str, list[str]]) -> str:
    """:func:`episode_problems` in one line: ``1 missing (a.png); 2 changed (b, c)``."""
    return "; ".join(f"{len(v)} {k} ({names(v)})" for k, v in problems.items() if v)


def verify_episode(out: Path, entry: dict, algorithm: str = ALGORITHM) -> bool:
    """True when ``out/entry['name']`` holds exactly the files listed, with their checksums."""
    return not any(episode_problems(out, entry, algorithm).values())


def check_out(out: Path, resume: bool = False, overwrite: bool = False) -> Path:
    """``out`` as a Path, created and writable; refuse a non-empty one unless ``resume`` or
    ``overwrite``, and with them one that holds no manifest (not a dataset: its files are
    none of ours to delete)."""
    out = Path(out)
    if resume and overwrite:
        raise ValueError("--resume and --overwrite: expected at most one of them")
    from testbed.output import check_outside_episodes, check_writable

    check_outside_episodes("--out", out)
    if out.exists() and not out.is_dir():
        raise FileExistsError(f"--out: {out} exists and is not a directory")
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        raise ValueError(f"--out: cannot write to {out} ({exc.strerror or exc})") from None
    check_writable("--out", out)
    others = sorted(p.name for p in out.iterdir() if p.name != LOCK and not p.name.startswith(PROBE))
    if others and not (resume or overwrite):
        raise FileExistsError(f"--out: {out} exists and is not empty; pass --resume to finish it "
                              "or --overwrite to replace it")
    # --overwrite deletes: the manifest must be ours, not any manifest.json (web extensions
    # have one); --resume reads it next and names what is wrong with it
    read = (lambda path: read_manifest(path.parent)) if overwrite else None
    refuse_foreign(out, others, MANIFEST, "a camtask render dataset", "--resume" if resume else "--overwrite", read)
    return out


def refuse_foreign(folder: Path | str, others: list[str], marker: str, what: str, flag: str,
                   read: Callable[[Path], object] | None = None) -> None:
    """Refuse ``flag`` (which empties or adds to ``folder``) when ``folder`` holds ``others``
    but not ``marker``, or a ``marker`` that ``read`` (given its path) refuses with a
    ValueError: it is not ``what``, so its files are none of ours to delete."""
    if not others:
        return
    why = f"no {marker}" if marker not in others else None
    if why is None and read is not None:
        try:
            read(Path(folder) / marker)
        except ValueError as exc:
            why = str(exc)
    if why is not None:
        raise FileExistsError(f"{flag}: {folder} is not {what} ({why}; it holds {names(others)}); "
                              "empty it yourself or choose another folder")


#: Bytes on disk per camera frame, as a fraction of its raw RGB size (W x H x 3): the noisy
#: frames take ~58 % as PNG (lab episodes, masks, silhouettes and the rest included) and
#: ~47 % as FFV1 video.
DISK_FRACTION = 0.6


def estimate_bytes(config: EpisodeConfig, scene, episodes: int) -> int:
    """About how many bytes ``episodes`` episodes of ``config`` take on disk (backgrounds included)."""
    n = len(config.cameras) if config.cameras else len(scene.cameras)
    cam = scene.cameras[0]
    return int(episodes * (config.frames + 1) * n * cam.width * cam.height * 3 * DISK_FRACTION)


def free_bytes(out: Path) -> tuple[int, Path]:
    """Free bytes on the file system that holds ``out`` (or its nearest existing parent), and that path."""
    probe = Path(out).absolute()
    while not probe.exists() and probe != probe.parent:
        probe = probe.parent
    return shutil.disk_usage(probe).free, probe


def check_space(out: Path, need: int, what: str, freed: int = 0) -> None:
    """Raise a one-line ValueError when the disk of ``out`` has less than ``need`` bytes free,
    counting ``freed`` bytes that ``--overwrite`` will delete first."""
    free, where = free_bytes(out)
    if free + freed < need:
        also = f" (and {size_text(freed)} that --overwrite would free)" if freed else ""
        raise ValueError(f"--out: {size_text(free)} free on {where}{also}; {what} needs about {size_text(need)}")


def size_text(n: float) -> str:
    """Bytes for messages, three significant digits, powers of 1000 (MB, GB, TB), in the
    largest unit of which there is at least one once rounded (never ``1e+03 MB``).

    >>> size_text(68_164_317), size_text(8.8e9), size_text(1_658_880), size_text(999_600_000)
    ('68.2 MB', '8.8 GB', '1.66 MB', '1 GB')
    """
    for scale, unit in ((1e12, "TB"), (1e9, "GB")):
        if float(f"{n / scale:.3g}") >= 1:
            return f"{n / scale:.3g} {unit}"
    return f"{n / 1e6:.3g} MB"


def prepare_output(out: Path, config: EpisodeConfig, episodes: int, resume: bool, overwrite: bool,
                   verified: Callable[[int, int], None] | None = None) -> dict[int, dict]:
    """Check and prepare ``out``; return the finished episodes to keep (index -> entry).

    Without ``resume`` or ``overwrite`` an existing non-empty ``out`` is refused; with
    ``overwrite`` it is emptied; with ``resume`` (the same arguments, or more episodes:
    episode i depends only on the seed and i, so a run can be extended) the manifest's
    episodes whose files verify are kept and everything else (unlisted or corrupt
    episode folders, temporary folders of killed runs) is removed; a kept episode
    rendered from another scene text than ``config``'s is refused
    (:func:`check_same_scene`). Then the manifest of the kept episodes is written (none
    on a fresh run: a run stopped before its first episode still names its arguments).
    Raises ValueError / FileExistsError before any work.

    verified : called as ``verified(files, total)`` after each listed episode is checked
        on resume (``files`` of the ``total`` listed), for a progress bar
    """
    out = check_out(out, resume, overwrite)
    existing = [p for p in out.iterdir() if p.name != LOCK]     # the lock: this run's own
    keep: dict[int, dict] = {}
    if overwrite:
        # the manifest last: deleting a large dataset takes a while, and a run stopped meanwhile
        # (Ctrl-C on seeing the wrong --out) left episodes without it, a folder that --overwrite
        # and --resume then refused as not a dataset; with it, --overwrite empties it again
        for p in sorted(existing, key=lambda p: p.name == MANIFEST):
            shutil.rmtree(p) if p.is_dir() and not p.is_symlink() else p.unlink()
    elif resume and existing:
        old = read_manifest(out)
        if old is not None:
            if _canonical_dict(old.get("config"), config) != config.to_dict():
                raise ValueError(f"--resume: {out / MANIFEST} was written with other arguments "
                                 f"({_diff(old, config)}); give the arguments of that run to finish it "
                                 "(the same scene string too: it is recorded in each meta.json), or "
                                 "--overwrite to start again")
            planned = int(old.get("episodes_planned", 0))
            if episodes < planned:                  # more is fine: episode i depends on the seed and i only
                raise ValueError(f"--resume: --episodes {episodes}, but the run planned {planned}: it can "
                                 "extend a run, not shrink it")
            algorithm = manifest_algorithm(old)
            listed = old.get("episodes", [])
            layout = int(old.get("episode_layout", 1))
            if listed and layout != EPISODE_LAYOUT:
                which = "an earlier" if layout < EPISODE_LAYOUT else "a later"
                raise ValueError(f"--resume: the episodes in {out} are of layout {layout} ({which} camtask), this "
                                 f"camtask writes layout {EPISODE_LAYOUT} (docs/dataset.md); finish the run with the "
                                 "camtask that started it, or use --overwrite to start again")
            total = sum(len(e["files"]) for e in listed)
            for entry in listed:
                if verify_episode(out, entry, algorithm):
                    check_same_scene(out, entry, config)
                    if algorithm != ALGORITHM:          # an older manifest: its episodes' checksums renewed
                        entry = entry | {"files": checksums(out / entry["name"])}
                    keep[int(entry["index"])] = entry
                if verified is not None:
                    verified(len(entry["files"]), total)
        remove_unlisted(out, keep)
        check_episode_names_free(out, keep, episodes)
    listing = ManifestWriter(out, config, episodes, keep)
    if not listing.on_disk():               # a finished run resumed on a full disk: nothing to write
        listing.flush()
    return keep


def check_episode_names_free(out: Path, keep: dict[int, dict], episodes: int) -> None:
    """Refuse (FileExistsError, before any work) a file or link of ``out`` named as an
    episode still to render: a run makes only folders there, so it is not removed as left
    behind (:func:`unlisted`), and the finished episode could not be renamed onto it.
    The names looked at are the folder's, not every episode's: ``--episodes`` may be large."""
    taken = []
    for p in Path(out).iterdir():
        if (number := re.fullmatch(r"episode_(\d{4,})", p.name)) is None:
            continue
        i = int(number.group(1))
        if i < episodes and i not in keep and p.name == episode_name(i):
            taken.append((i, p))
    if taken:
        i, path = min(taken)
        kind = "a link" if path.is_symlink() else "a folder that could not be deleted" if path.is_dir() \
            else "a file"
        raise FileExistsError(f"--resume: {path} is {kind}, not an episode folder, and episode {i} is to be "
                              "written there: move it away")


@contextlib.contextmanager
def exclusive(out: Path):
    """Hold ``out/LOCK`` (an exclusive ``flock``) while a run writes into ``out``.

    A second run into the same folder (a ``--resume`` or ``--overwrite`` in another
    terminal) would delete this one's temporary folders and rewrite its manifest; it is
    refused instead (FileExistsError), before it touches anything. The lock goes with the
    process, so a killed run leaves none (at most the empty file, which is ignored). On a
    file system without ``flock`` the run goes on with a warning.
    """
    path = Path(out) / LOCK
    fd = _lock(path, out)
    try:
        yield
    finally:
        if fd is not None:
            with contextlib.suppress(OSError):      # gone, or a lost mount: not the error to see
                os.unlink(path)
            os.close(fd)


def _lock(path: Path, out: Path) -> int | None:
    """The descriptor of ``path``, locked; None where the file system cannot lock."""
    while True:
        fd = os.open(path, os.O_RDWR | os.O_CREAT, 0o644)
        try:
            fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
        except OSError as exc:
            os.close(fd)
            if exc.errno in (errno.EWOULDBLOCK, errno.EAGAIN):
                raise FileExistsError(f"--out: another camtask render is writing to {out} (it holds {path}); "
                                      "wait for it to finish or stop it") from None
            print(f"warning: --out: cannot lock {path} ({exc.strerror}): a second run into {out} would not "
                  "be refused", file=sys.stderr)
            return None
        try:
            same = os.stat(path).st_ino == os.fstat(fd).st_ino
        except FileNotFoundError:
            same = False
        if same:
            return fd
        os.close(fd)                                # its holder deleted it meanwhile: lock the new one


def check_same_scene(out: Path, entry: dict, config: EpisodeConfig) -> None:
    """Refuse to resume with a scene file that has changed since episode ``entry`` was rendered
    (its meta.json holds the scene's text); nothing is checked when ``config`` has no text."""
    if not config.scene_yaml:
        return
    meta = json.loads((Path(out) / entry["name"] / "meta.json").read_text())
    if meta.get("scene_yaml") != config.scene_yaml:
        raise ValueError(f"--resume: {config.scene} is not the scene {entry['name']} was rendered from "
                         f"(its meta.json's scene_yaml); restore it, or use --overwrite to start again")


def unlisted(out: Path, entries: dict[int, dict]) -> list[Path]:
    """The episode folders of ``out`` not in ``entries``, the temporary folders of unfinished
    episodes, and the temporary files of a manifest or run_info.json being rewritten or of a
    check that ``out`` can be written (:data:`PROBE`) when the run was killed, sorted by name."""
    wanted = {episode_name(i) for i in entries}
    left = []
    for p in Path(out).iterdir():
        if p.name in wanted:
            continue
        if _RUN_FOLDER.fullmatch(p.name):                       # an episode, finished or not
            if p.is_dir() and not p.is_symlink():
                left.append(p)
        elif _RUN_FILE.fullmatch(p.name):                       # a manifest or run_info.json being written
            left.append(p)
    return sorted(left, key=lambda p: p.name)


#: The names a run gives what it writes into ``--out``, apart from the manifest and
#: run_info.json: only these are removed as left behind (a file ``episode_best.yaml`` there,
#: a user's, was deleted by ``--resume``).
_RUN_FOLDER = re.compile(r"episode_\d{4,}|\.episode_\d{4,}\..+\.tmp")
_RUN_FILE = re.compile(rf"\.({re.escape(MANIFEST)}|{re.escape(RUN_INFO)})\..+\.tmp|{re.escape(PROBE)}.+")


def remove_unlisted(out: Path, entries: dict[int, dict] | None = None) -> None:
    """Delete :func:`unlisted` folders, against ``entries`` (default: the manifest's).

    Only when nothing writes to ``out`` any more: after a run, once its workers have stopped.
    """
    if entries is None:
        m = read_manifest(out)
        entries = {int(e["index"]): e for e in (m or {}).get("episodes", [])}
    for p in unlisted(out, entries):
        if p.is_dir() and not p.is_symlink():
            shutil.rmtree(p, ignore_errors=True)
        else:
            p.unlink(missing_ok=True)


def _canonical_dict(was, config: EpisodeConfig):
    """A manifest's ``config`` as :func:`testbed.episodes.canonical` makes it when its scene
    is ``config``'s (an earlier camtask wrote ``people: 3`` for ``--people 3`` on a scene of 3
    people); anything else as it is."""
    if not isinstance(was, dict) or was.get("scene") != config.scene:
        return was
    return without_scene_own(was, config)


def _diff(old: dict, config: EpisodeConfig) -> str:
    new = config.to_dict()
    was = dict(_canonical_dict(old.get("config"), config) or {})
    keys = sorted(k for k in set(new) | set(was) if new.get(k) != was.get(k))
    return ", ".join(f"{k}: {was.get(k)!r} then, {new.get(k)!r} now" for k in keys)


def versions() -> dict:
    from importlib import metadata

    out = {"python": platform.python_version()}
    for dist in ("numpy", "opencv-python-headless", "pyrender2", "PyOpenGL", "shapely", "dask", "distributed",
                 "imageio-ffmpeg", "fpng", "isal", "blake3", "numba", "camtask"):
        try:
            out[dist] = metadata.version(dist)
        except metadata.PackageNotFoundError:
            pass
    return out


#: Packages whose versions do not change a dataset's bytes (Dask checks its own across a cluster).
NOT_IN_BYTES = ("python", "dask", "distributed")


def check_worker_versions(client) -> None:
    """Refuse a cluster whose workers run other versions of the packages that make the
    bytes (numpy, OpenCV, the encoders, camtask, ...) than this process: their episodes
    would differ from this machine's for the same seed. One line naming the first such
    worker and what differs.
    """
    here = versions()
    for worker, theirs in sorted(client.run(versions).items()):
        if changes := version_changes(theirs, here, "there", "here"):
            raise ValueError(f"--scheduler: worker {worker} has other package versions than this machine "
                             f"({changes}); its episodes would not be the same bytes")


def check_workers_ffmpeg(client) -> None:
    """Refuse (one line naming the first such worker) a cluster with a worker that has no
    ffmpeg to write ``--format video``'s videos: this machine's is checked before any work,
    a worker's own was found only at its first episode, failing the run there."""
    for worker, problem in sorted(client.run(_ffmpeg_problem).items()):
        if problem is not None:
            raise ValueError(f"--scheduler: worker {worker} cannot write --format video ({problem})")


def _ffmpeg_problem() -> str | None:
    """Why the worker that runs this has no ffmpeg (:func:`testbed.lossless.ffmpeg_exe`), or None."""
    from testbed.lossless import ffmpeg_exe

    try:
        ffmpeg_exe()
    except OSError as exc:
        return str(exc)
    return None


#: Seconds a file written here, or an episode folder that a worker has renamed into place,
#: may take to show on the other machines (a network file system).
SHARE_PATIENCE = 10.0


def check_workers_share(client, out: Path, patience: float = SHARE_PATIENCE) -> None:
    """Refuse a cluster with a worker that does not see ``out`` at the same path, or cannot
    write there: it would write its episodes where this process never finds them, or fail
    each one it takes. A file with a random token is written into ``out`` and read back on
    every worker, which also creates and removes a file beside it, for up to ``patience``
    seconds (a network file system may show a new file to other machines a little later).
    One line naming the first such worker.
    """
    import secrets

    folder = Path(out).absolute()
    token = secrets.token_hex(16)
    probe = folder / f"{PROBE}{token[:12]}"
    probe.write_text(token)
    try:
        deadline = time.monotonic() + patience
        while True:
            views = sorted(client.run(_worker_view, str(probe)).items())
            blind = [w for w, (seen, _) in views if seen != token]
            if not blind:
                for worker, (_, why) in views:
                    if why is not None:
                        raise ValueError(f"--scheduler: worker {worker} cannot write to {folder} ({why}); --out "
                                         "must be a folder that every worker can write to")
                return
            if time.monotonic() >= deadline:
                raise ValueError(f"--scheduler: worker {blind[0]} does not see {folder}; --out must be a folder "
                                 "that every worker shares, at the same path (a shared file system)")
            time.sleep(0.5)
    finally:
        probe.unlink(missing_ok=True)


def _read_text(path: str) -> str | None:
    """The text of ``path`` on the worker that runs this, or None."""
    try:
        return Path(path).read_text()
    except OSError:
        return None


def _worker_view(path: str) -> tuple[str | None, str | None]:
    """The text of the probe ``path`` on the worker that runs this (None when it cannot read
    it), and why it cannot create a file beside it (None when it can: it made and removed one,
    named as ``path`` and a random suffix, so that no two workers share it)."""
    import secrets

    text = _read_text(path)
    if text is None:
        return None, None
    mine = f"{path}.{secrets.token_hex(6)}"
    try:
        os.close(os.open(mine, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o644))
        os.unlink(mine)
    except OSError as exc:
        return text, exc.strerror or str(exc)
    return text, None


def version_changes(a: dict, b: dict, a_name: str, b_name: str) -> str:
    """The packages that make the bytes whose versions differ between two :func:`versions`
    records, as ``"numpy 2.3.0 then, 2.4.6 now"`` (``a_name``, ``b_name``); "" if none."""
    keys = sorted(k for k in set(a) | set(b) if k not in NOT_IN_BYTES and a.get(k) != b.get(k))
    return ", ".join(f"{k} {a.get(k)} {a_name}, {b.get(k)} {b_name}" for k in keys)


def generate(config: EpisodeConfig, episodes: int, out: Path, keep: dict[int, dict], client=None,
             progress: Callable[[int], None] | None = None,
             run_info: dict | None = None) -> dict[int, dict]:
    """Render the episodes not in ``keep`` into ``out``; return all finished entries (those
    of the episodes rendered here without their ``files``, which only the manifest keeps).

    client : a ``distributed.Client`` or None (in this process, one episode after the other,
        each writing and processing its frames on a second thread when there is a second core)
    progress : called with a number of frames finished (per frame in-process; on Dask
        from the frames in the workers' temporary folders, counted at each finished episode
        and at least every 0.25 s)
    An episode whose worker dies is rescheduled by the Dask scheduler, up to its
    ``distributed.scheduler.allowed-failures`` (3 by default) times, after which it raises
    ``distributed.KilledWorker``; an episode that raises stops the run, as in-process.
    The manifest is rewritten as episodes finish (:class:`ManifestWriter`: after each one
    while rewriting is cheap, less often as it grows) and at the end; on an error, the
    episodes finished so far are listed and stay valid, and the error is re-raised. What
    the manifest does not list (temporary folders of dead workers) is removed when every
    episode has finished, or in-process; after an error on Dask, workers may still be
    writing: the caller calls :func:`remove_unlisted` once they have stopped.
    """
    out = Path(out)
    done = dict(keep)
    todo = (i for i in range(episodes) if i not in done)     # lazily: --episodes may be large
    info = {"started": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "host": socket.gethostname(),
            "versions": versions(), "argv": sys.argv[1:]} | (run_info or {})
    earlier = earlier_runs(out)                     # a resumed run's predecessors, kept in run_info.json
    if earlier and keep and (changes := version_changes(earlier[-1].get("versions", {}), info["versions"],
                                                        "then", "now")):
        print(f"warning: --resume: other package versions than the run before ({changes}): the episodes it "
              "rendered may differ from this run's in their bytes", file=sys.stderr)
    hosts: dict[str, str] = {}
    stages: dict[str, dict] = {}
    complete = False
    listing = ManifestWriter(out, config, episodes, keep, on_disk=True)   # as prepare_output wrote it

    def finished(entry: dict, host: str, secs: dict) -> None:
        done[entry["index"]] = {k: v for k, v in entry.items() if k != "files"}   # the manifest has them
        hosts[entry["name"]] = host
        stages[entry["name"]] = {k: round(v, 3) for k, v in sorted(secs.items())}
        listing.add(entry)

    try:
        if client is None:
            overlap = default_workers() > 1         # a second core writes while this one renders
            for i in todo:
                secs: dict = {}
                entry = render_episode(config, i, str(out), progress, secs, overlap=overlap)
                finished(entry, socket.gethostname(), secs)
        else:
            _generate_on_dask(client, config, out, todo, finished, progress)
        listing.flush()
        complete = True
    finally:
        if not complete:                            # listed before anything unlisted is removed
            with contextlib.suppress(OSError):      # (a full disk: the first error is the one to see)
                listing.flush()
        if complete or client is None:              # else cancelled episodes may still be running
            remove_unlisted(out, done)              # temporary folders of workers that died
        info |= {"finished": time.strftime("%Y-%m-%dT%H:%M:%S%z"), "episodes_done": len(done),
                 "episode_hosts": dict(sorted(hosts.items())), "episode_seconds": dict(sorted(stages.items()))}
        if earlier:
            info["earlier_runs"] = earlier
        with contextlib.suppress(*(() if complete else (OSError,))):    # the first error is the one to see
            write_json_atomic(out / RUN_INFO, info)
    return done


def _generate_on_dask(client, config: EpisodeConfig, out: Path, todo: Iterator[int],
                      finished: Callable[[dict, str, dict], None],
                      progress: Callable[[int], None] | None = None) -> None:
    """Render the episodes ``todo`` on ``client``'s workers, calling ``finished(entry, host,
    seconds)`` as each one ends; see :func:`generate`. The episodes not finished are
    cancelled when this returns or raises."""
    ready = threading.Event()               # set as each episode's task ends

    def submit(i: int):
        fut = client.submit(_remote_episode, config, i, str(out.absolute()), pure=False,
                            key=episode_key(i))
        fut.add_done_callback(lambda _: ready.set())
        return fut

    # index -> future of the episodes not yet listed; a listed one is dropped at once, so
    # the cluster lets go of its result (a checksum per file: ~3 MB for 300 frames). No
    # distributed.wait(timeout=...): its TimeoutError's traceback kept every future it
    # was given alive until the garbage collector broke the cycle. At most
    # in_flight(client) episodes are submitted at a time: 200 000 submitted at once
    # slowed rendering tenfold (and took minutes to cancel), 10**12 filled the memory.
    pending: dict = {}
    shown: dict[int, int] = {}              # frames counted per episode so far
    alone = False                           # no worker at the last look (said once, until one comes)

    def top_up() -> None:
        nonlocal alone
        threads = client.nthreads()
        for i in itertools.islice(todo, max(0, in_flight(client, threads) - len(pending))):
            pending[i], shown[i] = submit(i), 0
        # an existing cluster's workers all gone (a local cluster's nanny restarts its own: no word)
        if pending and not threads and not alone and getattr(client, "cluster", None) is None:
            from tqdm import tqdm

            n = len(pending)
            tqdm.write(f"warning: no Dask worker is left in the cluster at {client.scheduler.address}; "
                       f"{n} episode{'' if n == 1 else 's'} wait{'s' if n == 1 else ''} for one (Ctrl-C stops)",
                       file=sys.stderr)                                         # over the bar
        alone = not threads

    def show(index: int, frames: int) -> None:
        if progress is not None and frames > shown[index]:
            progress(frames - shown[index])
            shown[index] = frames

    try:
        top_up()
        while pending:
            stops.check()                   # a Ctrl-C that a future's finalizer swallowed
            ready.clear()                   # an episode ending from here on wakes the wait below
            for index in [i for i, f in pending.items() if f.done()]:
                entry, host, secs = pending[index].result()    # re-raises the episode's error
                check_written_here(out, entry, host)
                finished(entry, host, secs)
                del pending[index]
                show(index, entry["frames"])
                del shown[index]
            top_up()
            for index, frames in (frames_in_progress(out) if progress else {}).items():
                if index in shown:
                    show(index, min(frames, config.frames - 1))
            if pending:                     # wake at the next finished episode, or in 0.25 s
                ready.wait(0.25)
    finally:
        for f in pending.values():
            f.cancel()


class NotShared(Exception):
    """An episode that a worker wrote where this process does not see it."""


def check_written_here(out: Path, entry: dict, host: str) -> None:
    """Raise :class:`NotShared` unless the episode folder of ``entry``, which a worker on
    ``host`` has finished, shows in ``out`` within :data:`SHARE_PATIENCE` seconds.

    :func:`check_workers_share` checks the workers of the cluster when the run starts; one
    that joins later (an adaptive cluster adding nodes, each with its own ``/scratch``) writes
    to its own disk, and its episodes were listed though no folder of them is in ``out``.
    """
    folder = Path(out).absolute() / entry["name"]
    deadline = time.monotonic() + SHARE_PATIENCE
    while not folder.is_dir():
        if time.monotonic() >= deadline:
            raise NotShared(f"episode {entry['index']}: a worker on {host} wrote it where this machine does not see "
                            f"it (no {folder} here after {SHARE_PATIENCE:g} s); --out must be a folder that every "
                            "worker shares, at the same path (a worker that joined the cluster after the run started?)")
        time.sleep(0.1)


def earlier_runs(out: Path) -> list[dict]:
    """The runs recorded in ``out``'s run_info.json, oldest first (none for a new folder).

    A run rewrites run_info.json at its end with its own record at the top level; the
    records of the runs before it into the same folder (a run and its ``--resume`` s) go
    to ``earlier_runs``, so the hosts, versions and times of every kept episode survive.
    """
    try:
        last = json.loads((Path(out) / RUN_INFO).read_text())
    except (OSError, ValueError):
        return []
    if not isinstance(last, dict):
        return []
    before = last.pop("earlier_runs", [])
    return [*(before if isinstance(before, list) else []), last]


def frames_in_progress(out: Path) -> dict[int, int]:
    """Frames written so far by the episodes being rendered: mask files of their first
    camera in their temporary folders (``DIR/.episode_NNNN.*.tmp``), by episode index."""
    counts: dict[int, int] = {}
    for tmp in Path(out).glob(".episode_*.tmp"):
        try:
            index = int(tmp.name.split(".")[1].split("_")[1])
            first = min((tmp / "masks").iterdir())
            counts[index] = max(counts.get(index, 0), sum(1 for _ in first.iterdir()))
        except (ValueError, IndexError, OSError):
            continue
    return counts


def in_flight(client, threads: dict | None = None) -> int:
    """How many episodes to keep submitted to ``client``: two per worker thread (one running,
    one queued, so no thread waits for the next submission), at least 4 (no worker has
    joined an external scheduler yet). threads : ``client.nthreads()``, if known."""
    return max(4, 2 * sum((client.nthreads() if threads is None else threads).values()))


def episode_key(index: int) -> str:
    """The Dask key of episode ``index`` in this run: unique per process and call."""
    return f"episode-{index}-{os.getpid()}-{time.time_ns()}"


def episode_of_key(key) -> int:
    """The episode index of an :func:`episode_key`.

    >>> episode_of_key(episode_key(12))
    12
    """
    return int(str(key).split("-")[1])


def _remote_episode(config: EpisodeConfig, index: int, out: str) -> tuple[dict, str, dict]:
    seconds: dict = {}
    return render_episode(config, index, out, seconds=seconds), socket.gethostname(), seconds
