"""camtask render: bad input gives one line and exit code 2 before any work starts."""

import json
import os
import shutil
import socket
from pathlib import Path

import pytest

from testbed.cli import main


def run(capsys, *argv):
    capsys.readouterr()
    code = main(["render", *argv])
    err = capsys.readouterr().err.strip().splitlines()
    return code, err[-1] if err else ""


@pytest.mark.parametrize(("argv", "message"), [
    (["--episodes", "0"], "--episodes: expected an integer >= 1, got 0"),
    (["--frames", "-1"], "--frames: expected an integer >= 1, got -1"),
    (["--workers", "-2"], "--workers: expected an integer >= 0, got -2"),
    (["--workers", "-1"], "--workers: expected an integer >= 0, got -1"),
    (["--cameras", "3,99"], "--cameras: expected distinct camera numbers"),
    (["--cameras", "1,x"], "--cameras: expected comma-separated camera numbers, got '1,x'"),
    (["--cameras", ","], "--cameras: expected distinct camera numbers among 1..16, got []"),
    (["--people", "17"], "expected at most 16"),
    (["--seed", "-1"], "--seed: expected an integer in 0..4294967295, got -1"),
])
def test_bad_arguments(tmp_path, capsys, argv, message):
    out = tmp_path / "out"
    code, line = run(capsys, "lab", "--out", str(out), "--workers", "0", *argv)
    assert code == 2 and line.startswith("camtask render: error: ") and message in line
    assert not out.exists()


def test_bad_scene_file(tmp_path, capsys):
    bad = tmp_path / "bad.yaml"
    bad.write_text("room: {width: -1}\n")
    code, line = run(capsys, str(bad), "--out", str(tmp_path / "out"), "--workers", "0")
    assert code == 2 and line.startswith("camtask render: error: scene: missing key")
    assert not (tmp_path / "out").exists()


@pytest.mark.parametrize(("edit", "message"), [
    # passes the scene's own checks, but its image cannot be rectified to a level camera
    (lambda c: (c["cameras"]["poses"][1].update(pitch_deg=60.0),
                c["cameras"]["intrinsics"].update(hfov_deg=60.0, distortion=[-0.3, 0.1, 0, 0, 0])),
     ("camera 2: field of view too wide, or pitch too steep, to rectify to a level camera (every pixel must look "
     "less than 87 degrees from the level forward direction: check its pitch_deg, hfov_deg and distortion)")),
    (lambda c: c["people"].update(count=17, radius=0.1),
     "people.count: silhouettes store one bit per person in a 16-bit PNG; expected at most 16, got 17"),
])
def test_a_scene_that_cannot_be_rendered_is_refused_before_any_work(tmp_path, capsys, edit, message):
    import yaml

    from scene import scene_path

    config = yaml.safe_load(scene_path("lab").read_text())
    edit(config)
    path = tmp_path / "scene.yaml"
    path.write_text(yaml.safe_dump(config))
    code, line = run(capsys, str(path), "--out", str(tmp_path / "out"), "--workers", "0")
    assert code == 2 and line == f"camtask render: error: {message}"
    assert not (tmp_path / "out").exists()


def test_unwritable_output(tmp_path, capsys):
    (tmp_path / "file").write_text("x")
    code, line = run(capsys, "lab", "--out", str(tmp_path / "file" / "sub"), "--workers", "0")
    assert code == 2 and "--out: cannot write to" in line


def test_non_empty_output_is_refused(tmp_path, capsys):
    out = tmp_path / "ds"
    out.mkdir()
    (out / "keep.txt").write_text("x")
    code, line = run(capsys, "lab", "--out", str(out), "--workers", "0")
    assert code == 2 and "not empty" in line and "--resume" in line and "--overwrite" in line
    assert (out / "keep.txt").read_text() == "x"


@pytest.mark.parametrize("mode", ["--resume", "--overwrite"])
def test_a_folder_that_is_not_a_dataset_is_neither_resumed_nor_overwritten(tmp_path, capsys, mode):
    """--overwrite empties DIR and --resume adds episodes to it: only to a dataset (it has a manifest)."""
    out = tmp_path / "work"
    (out / "src").mkdir(parents=True)
    for name in ("notes.txt", "b", "c", "d"):
        (out / name).write_text("x")
    code, line = run(capsys, "lab", "--out", str(out), "--workers", "0", mode)
    assert code == 2 and line == (f"camtask render: error: {mode}: {out} is not a camtask render dataset (no "
                                  "manifest.json; it holds b, c, d and 2 more); empty it yourself or choose another folder")
    assert sorted(p.name for p in out.iterdir()) == ["b", "c", "d", "notes.txt", "src"]


def test_unreachable_scheduler(tmp_path, capsys):
    code, line = run(capsys, "lab", "--out", str(tmp_path / "new" / "out"), "--scheduler", "tcp://127.0.0.1:9")
    assert code == 2 and "cannot reach a Dask scheduler" in line
    assert not (tmp_path / "new").exists()                # the folders this run made are gone again


def test_a_lost_scheduler_is_one_line():
    """The scheduler of an existing cluster dies mid-run: Dask cancels the futures or closes the comm."""
    from distributed.client import FutureCancelledError
    from distributed.comm.core import CommClosedError

    from testbed.commands.render import machine_error

    lost = FutureCancelledError("episode-0003", reason="scheduler-connection-lost")
    closed = CommClosedError("in <TCP (closed) ConnectionPool.gather local=tcp://127.0.0.1:5>: ConnectionResetError")
    for exc, reason in ((lost, "scheduler-connection-lost"), (closed, "CommClosedError")):
        assert machine_error(exc, "tcp://10.0.0.5:8786") == (
            f"--scheduler: lost the connection to tcp://10.0.0.5:8786 ({reason}); episodes running on its "
            "workers may still finish into temporary folders")
    assert machine_error(lost) is None                    # a local cluster: not this machine's error


def test_full_disk_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    import collections

    from testbed import generate

    usage = collections.namedtuple("usage", "total used free")
    seen = []
    monkeypatch.setattr(generate.shutil, "disk_usage", lambda path: seen.append(path) or usage(10**12, 0, 50 * 10**6))
    out = tmp_path / "new" / "ds"
    code, line = run(capsys, "lab", "--out", str(out), "--frames", "100", "--workers", "0")
    # 101 x 16 frames of 640 x 480 x 3 bytes at DISK_FRACTION 0.6
    assert code == 2 and line == f"camtask render: error: --out: 50 MB free on {out}; one episode needs about 894 MB"
    assert seen == [out] and not (tmp_path / "new").exists()     # checked once made, then removed again


def test_manifest_before_the_first_episode_and_unlisted_folders_removed(tmp_path):
    import json

    from pipeline import load_params
    from testbed.episodes import EpisodeConfig
    from testbed.generate import prepare_output, remove_unlisted

    config = EpisodeConfig("lab", None, (2, 7), 4, 1, "png", load_params().to_dict())
    out = tmp_path / "data"
    assert prepare_output(out, config, 3, False, False) == {}
    m = json.loads((out / "manifest.json").read_text())
    assert m["episodes"] == [] and m["episodes_planned"] == 3 and m["config"] == config.to_dict()
    # a run stopped before its first episode is still recognised
    other = EpisodeConfig("lab", None, (2, 7), 5, 1, "png", load_params().to_dict())
    with pytest.raises(ValueError, match="frames: 4 then, 5 now.*give the arguments of that run"):
        prepare_output(out, other, 3, True, False)
    # the scene string is an argument too: meta.json records it
    moved = EpisodeConfig("./lab.yaml", None, (2, 7), 4, 1, "png", load_params().to_dict())
    with pytest.raises(ValueError, match="scene: 'lab' then, './lab.yaml' now"):
        prepare_output(out, moved, 3, True, False)
    for name in ("episode_0001", ".episode_0002.x1.tmp", "notes"):
        (out / name).mkdir()
    remove_unlisted(out)
    assert sorted(p.name for p in out.iterdir()) == ["manifest.json", "notes"]


@pytest.mark.parametrize("mode", ["--resume", "--overwrite"])
def test_a_folder_another_run_is_writing_is_refused(tmp_path, capsys, mode):
    from testbed.generate import LOCK, exclusive

    out = tmp_path / "ds"
    out.mkdir()
    (out / "manifest.json").write_text('{"episodes": []}')
    with exclusive(out):                          # as a run in another terminal holds it
        code, line = run(capsys, "lab", "--out", str(out), "--workers", "0", mode)
        assert code == 2 and line == (f"camtask render: error: --out: another camtask render is writing to {out} "
                                      f"(it holds {out / LOCK}); wait for it to finish or stop it")
        assert (out / "manifest.json").read_text() == '{"episodes": []}' and (out / LOCK).exists()
    assert sorted(p.name for p in out.iterdir()) == ["manifest.json"]   # the holder removed its lock


def test_a_left_lock_file_is_taken_over(tmp_path):
    """A killed run's lock file (no lock held) neither blocks the next run nor counts as content."""
    from testbed.generate import LOCK, check_out, exclusive

    out = tmp_path / "ds"
    out.mkdir()
    (out / LOCK).write_bytes(b"")
    check_out(out)                                # not "exists and is not empty"
    with exclusive(out):
        assert (out / LOCK).exists()
    assert not (out / LOCK).exists()


def test_overwrite_under_the_lock_keeps_the_lock(tmp_path):
    """--overwrite empties the folder but for this run's lock: a second run is still refused."""
    from pipeline import load_params
    from testbed.episodes import EpisodeConfig
    from testbed.generate import LOCK, exclusive, prepare_output

    config = EpisodeConfig("lab", None, (2,), 1, 0, "png", load_params().to_dict())
    out = tmp_path / "ds"
    prepare_output(out, config, 1, False, False)
    (out / "episode_0000").mkdir()
    with exclusive(out):
        assert prepare_output(out, config, 1, False, True) == {}
        assert sorted(p.name for p in out.iterdir()) == [LOCK, "manifest.json"]
        with pytest.raises(FileExistsError, match="another camtask render is writing"), exclusive(out):
            pass


def test_workers_with_other_package_versions_are_refused():
    from testbed.generate import check_worker_versions, versions

    class Cluster:                                  # client.run(f): f's result on every worker
        def __init__(self, *changes):
            self.changes = changes

        def run(self, fn):
            return {f"tcp://10.0.0.{i}:1": fn() | change for i, change in enumerate(self.changes)}

    check_worker_versions(Cluster({}, {"python": "3.11.0", "dask": "1.0"}))   # not in the bytes: fine
    here = versions()["numpy"]
    with pytest.raises(ValueError) as err:
        check_worker_versions(Cluster({}, {"numpy": "1.0.0"}))
    assert str(err.value) == (f"--scheduler: worker tcp://10.0.0.1:1 has other package versions than this machine "
                              f"(numpy 1.0.0 there, {here} here); its episodes would not be the same bytes")


def test_manifest_writer_gives_the_bytes_of_the_whole_manifest_serialised(tmp_path):
    import json

    from pipeline import load_params
    from testbed.episodes import EpisodeConfig
    from testbed.generate import MANIFEST, ManifestWriter, manifest

    config = EpisodeConfig("lab", None, (2, 7), 4, 1, "png", load_params().to_dict())
    entries = {i: {"index": i, "name": f"episode_{i:04d}", "seed": 1, "spawn_key": [i], "frames": 4,
                   "files": {"a/b.png": "00ff", 'odd "name"\n\u00e9.txt': "11", "z": "22"}} for i in (3, 0, 1)}
    for some in ({}, {0: entries[0]}, entries):
        writer = ManifestWriter(tmp_path, config, 5, some)
        writer.flush()
        expected = json.dumps(manifest(config, 5, some), indent=1, sort_keys=True) + "\n"
        assert (tmp_path / MANIFEST).read_text() == expected


def test_manifest_writer_rewrites_no_sooner_than_its_pace_allows(tmp_path, monkeypatch):
    """Rewrites after each episode while they are cheap; a slow one defers the next; flush catches up."""
    import json

    from testbed import generate
    from testbed.episodes import EpisodeConfig

    clock = {"now": 100.0}
    monkeypatch.setattr(generate.time, "perf_counter", lambda: clock["now"])
    real = generate.ManifestWriter.chunks

    def slow_chunks(self):                        # every rewrite takes 2 s of the fake clock
        clock["now"] += 2.0
        return real(self)

    monkeypatch.setattr(generate.ManifestWriter, "chunks", slow_chunks)
    writer = generate.ManifestWriter(tmp_path, EpisodeConfig("lab", None, None, 1, 0), 9, {})
    listed = lambda: [e["index"] for e in json.loads((tmp_path / "manifest.json").read_text())["episodes"]]
    entry = lambda i: {"index": i, "name": f"episode_{i:04d}", "files": {}}
    writer.add(entry(0))                          # nothing written yet: due at once
    assert listed() == [0]
    clock["now"] += 2 * writer.PACE - 0.5         # not yet PACE x 2 s since then
    writer.add(entry(1))
    assert listed() == [0]
    clock["now"] += 0.5
    writer.add(entry(2))
    assert listed() == [0, 1, 2]
    writer.add(entry(3))
    writer.flush()
    assert listed() == [0, 1, 2, 3]
    writer.flush()                                # nothing new: not rewritten
    assert clock["now"] == 100.0 + 2 + 2 * writer.PACE + 2 + 2


def test_manifest_writer_of_a_file_on_disk_rewrites_it_only_for_a_new_episode(tmp_path):
    """on_disk: the file lists these episodes already (a finished run resumed): flush writes nothing."""
    from testbed.episodes import EpisodeConfig
    from testbed.generate import ManifestWriter

    config = EpisodeConfig("lab", None, None, 1, 0)
    entry = lambda i: {"index": i, "name": f"episode_{i:04d}", "files": {}}
    writer = ManifestWriter(tmp_path, config, 2, {0: entry(0)}, on_disk=True)
    writer.flush()
    assert not (tmp_path / "manifest.json").exists()
    writer.add(entry(1))
    listed = json.loads((tmp_path / "manifest.json").read_text())["episodes"]
    assert [e["index"] for e in listed] == [0, 1]


def test_workers_that_do_not_see_the_output_folder_are_refused(tmp_path):
    from testbed.generate import _read_text, check_workers_share

    class Cluster:                                  # client.run(f, *args): f's result on every worker
        def __init__(self, *sees):
            self.sees = sees

        def run(self, fn, path):                    # a worker that does not see it finds no file there
            return {f"tcp://10.0.0.{i}:1": fn(path if sees else f"{path}.elsewhere") for i, sees in enumerate(self.sees)}

    check_workers_share(Cluster(True, True), tmp_path)
    with pytest.raises(ValueError) as err:
        check_workers_share(Cluster(True, False), tmp_path, patience=0.6)
    assert str(err.value) == (f"--scheduler: worker tcp://10.0.0.1:1 does not see {tmp_path}; --out must be a "
                              "folder that every worker shares, at the same path (a shared file system)")
    assert list(tmp_path.iterdir()) == []           # the probe is gone either way
    from testbed.generate import PROBE, check_out

    (tmp_path / f"{PROBE}0123").write_text("left by a killed run")
    check_out(tmp_path)                             # not content: not "exists and is not empty"
    assert _read_text(str(tmp_path / "none")) is None


def test_workers_that_cannot_write_the_output_folder_are_refused(tmp_path, monkeypatch):
    """A worker that sees --out but cannot write there (a read-only mount, another user on
    the shared disk) failed every episode it took, after the run had started, with a bare
    "[Errno 30] Read-only file system: '.../.episode_0000.<random>.tmp'" and "--resume
    finishes the run"; it is refused before any work, as a worker that does not see it."""
    import errno

    from testbed.generate import check_workers_share

    def read_only(*args, **kwargs):
        raise OSError(errno.EROFS, "Read-only file system")

    class Cluster:                                  # client.run(f, *args): f's result on every worker
        def run(self, fn, *args):
            first = fn(*args)
            with monkeypatch.context() as m:        # the second worker's mount is read-only
                m.setattr(os, "open", read_only)
                m.setattr(os, "mkdir", read_only)
                second = fn(*args)
            return {"tcp://10.0.0.0:1": first, "tcp://10.0.0.1:1": second}

    with pytest.raises(ValueError) as err:
        check_workers_share(Cluster(), tmp_path, patience=0.6)
    assert str(err.value) == (f"--scheduler: worker tcp://10.0.0.1:1 cannot write to {tmp_path} (Read-only file "
                              "system); --out must be a folder that every worker can write to")
    assert list(tmp_path.iterdir()) == []           # no probe left


def test_workers_without_ffmpeg_are_refused_for_video(tmp_path, monkeypatch):
    """--format video checked this machine's ffmpeg before any work, not a --scheduler
    worker's: a worker without one failed the run at its first episode."""
    from testbed.generate import check_workers_ffmpeg

    class Cluster:                                  # client.run(f): f's result on every worker
        def run(self, fn):
            first = fn()
            with monkeypatch.context() as m:        # the second worker's IMAGEIO_FFMPEG_EXE names nothing
                m.setenv("IMAGEIO_FFMPEG_EXE", str(tmp_path / "no-ffmpeg"))
                second = fn()
            return {"tcp://10.0.0.0:1": first, "tcp://10.0.0.1:1": second}

    with pytest.raises(ValueError) as err:
        check_workers_ffmpeg(Cluster())
    assert str(err.value) == (f"--scheduler: worker tcp://10.0.0.1:1 cannot write --format video (ffmpeg: "
                              f"'{tmp_path / 'no-ffmpeg'}' (IMAGEIO_FFMPEG_EXE) is not an executable file; install "
                              "imageio-ffmpeg's binaries or point IMAGEIO_FFMPEG_EXE at an ffmpeg)")


def test_out_inside_an_episode_of_a_dataset_is_refused(tmp_path, capsys):
    dataset = tmp_path / "ds"
    (dataset / "episode_0002").mkdir(parents=True)
    (dataset / "manifest.json").write_text("{}")
    out = dataset / "episode_0002" / "nested"
    code, line = run(capsys, "lab", "--out", str(out), "--workers", "0", "--frames", "1")
    assert code == 2 and "is inside" in line and "an episode of the dataset" in line
    assert not out.exists()


def test_resume_removes_the_temporary_files_of_a_killed_manifest_rewrite_or_probe(tmp_path):
    from testbed.generate import remove_unlisted, unlisted

    out = tmp_path / "ds"
    out.mkdir()
    (out / "manifest.json").write_text('{"episodes": []}')
    # and the probes of a run killed while it checked that --out (or each worker) can write
    strays = [out / ".camtask-probe.3f9a1c2b7d4e", out / ".camtask-probe.3f9a1c2b7d4e.a1b2c3",
              out / ".camtask-probe.write-test.4242", out / ".manifest.json.k2x9.tmp", out / ".run_info.json.a1b2.tmp"]
    for p in strays:
        p.write_text("half")
    (out / "notes.manifest.json.tmp").write_text("not ours")
    assert unlisted(out, {}) == sorted(strays)
    remove_unlisted(out)
    assert sorted(p.name for p in out.iterdir()) == ["manifest.json", "notes.manifest.json.tmp"]


def test_resuming_a_finished_run_does_not_rewrite_its_manifest(tmp_path, monkeypatch):
    """A finished run resumed on a full disk needs no space: the manifest is not rewritten."""
    from pipeline import files, load_params
    from testbed.episodes import EpisodeConfig
    from testbed.generate import prepare_output

    config = EpisodeConfig("lab", None, (2, 7), 4, 1, "png", load_params().to_dict())
    out = tmp_path / "data"
    prepare_output(out, config, 3, False, False)

    def full(*args, **kwargs):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(files, "write_atomic", full)
    assert prepare_output(out, config, 3, True, False) == {}
    with pytest.raises(OSError, match="No space"):            # what changes must still be written
        prepare_output(out, config, 4, True, False)


def _prepared(tmp_path, episodes: int):
    """A lab run of cameras 2 and 7, one frame an episode, seed 1, PNG frames, and
    tmp_path/data prepared for ``episodes`` episodes; returns (config, out)."""
    from pipeline import load_params
    from testbed.episodes import EpisodeConfig
    from testbed.generate import prepare_output

    config = EpisodeConfig("lab", None, (2, 7), 1, 1, "png", load_params().to_dict())
    out = tmp_path / "data"
    prepare_output(out, config, episodes, False, False)
    return config, out


@pytest.mark.parametrize(("cores", "overlap"), [(1, False), (2, True)])
def test_in_process_episodes_write_on_a_second_thread_only_with_a_second_core(tmp_path, monkeypatch, cores,
                                                                               overlap):
    from testbed import generate as gen

    config, out = _prepared(tmp_path, 2)
    asked = []

    def episode(config, i, out, progress, seconds, overlap):
        asked.append(overlap)
        return fake_episode(config, i, out)

    monkeypatch.setattr(gen, "render_episode", episode)
    monkeypatch.setattr(gen, "default_workers", lambda: cores)
    gen.generate(config, 2, out, {})
    assert asked == [overlap, overlap]


def test_an_error_lists_the_episodes_finished_since_the_last_rewrite(tmp_path, monkeypatch):
    """The manifest is rewritten at the error: the episodes finished meanwhile are kept, not removed."""
    from testbed import generate as gen

    config, out = _prepared(tmp_path, 3)

    def episode(config, index, out, *args, **kwargs):
        if index == 2:
            raise RuntimeError("episode 2 failed")
        return fake_episode(config, index, out)

    monkeypatch.setattr(gen, "render_episode", episode)
    monkeypatch.setattr(gen.ManifestWriter, "PACE", 1e12)     # no rewrite after the first
    with pytest.raises(RuntimeError, match="episode 2 failed"):
        gen.generate(config, 3, out, {})
    assert [e["index"] for e in json.loads((out / "manifest.json").read_text())["episodes"]] == [0, 1]
    assert (out / "episode_0001").is_dir()


def test_generate_returns_the_entries_without_their_files(tmp_path, monkeypatch):
    """Only the manifest keeps each file's checksum: ~3 MB an episode of 300 frames."""
    from testbed import generate as gen

    config, out = _prepared(tmp_path, 2)

    def episode(config, index, out, *args, **kwargs):
        return fake_episode(config, index, out) | {"files": {"meta.json": "00"}}

    monkeypatch.setattr(gen, "render_episode", episode)
    done = gen.generate(config, 2, out, {})
    assert sorted(done) == [0, 1] and not any("files" in e for e in done.values())
    listed = json.loads((out / "manifest.json").read_text())["episodes"]
    assert [e["files"] for e in listed] == [{"meta.json": "00"}] * 2


def test_resuming_a_finished_run_writes_its_run_info_alone(tmp_path, monkeypatch):
    """No episode left to render: the manifest prepare_output found on disk is not written again."""
    from pipeline import files
    from testbed import generate as gen

    config, out = _prepared(tmp_path, 2)
    monkeypatch.setattr(gen, "render_episode", lambda config, i, out, *args, **kw: fake_episode(config, i, out))
    gen.generate(config, 2, out, {})
    keep = gen.prepare_output(out, config, 2, True, False)
    written = []
    real = files.write_atomic
    monkeypatch.setattr(files, "write_atomic", lambda path, data: (written.append(Path(path).name), real(path, data)))
    assert sorted(gen.generate(config, 2, out, keep)) == [0, 1]
    assert written == ["run_info.json"]


def test_a_full_disk_names_the_file_it_could_not_write(tmp_path, monkeypatch):
    import errno

    from pipeline.files import write_atomic

    def full(src, dst):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr("os.replace", full)
    target = tmp_path / "manifest.json"
    with pytest.raises(OSError, match=f"cannot write {target}: No space left on device") as info:
        write_atomic(target, b"{}")
    assert str(info.value) == f"cannot write {target}: No space left on device"
    assert info.value.errno == errno.ENOSPC and list(tmp_path.iterdir()) == []


def test_run_info_that_cannot_be_written_after_a_finished_run_is_the_error(tmp_path, monkeypatch):
    """Nothing else went wrong: the run's record lost is the error to see."""
    from testbed import generate as gen

    config, out = _prepared(tmp_path, 2)

    def run_info(path, data):
        raise OSError(f"cannot write {path}: No space left on device")

    monkeypatch.setattr(gen, "render_episode", lambda config, i, out, *args, **kw: fake_episode(config, i, out))
    monkeypatch.setattr(gen, "write_json_atomic", run_info)
    with pytest.raises(OSError, match="run_info.json: No space"):
        gen.generate(config, 2, out, {})
    assert [e["index"] for e in json.loads((out / "manifest.json").read_text())["episodes"]] == [0, 1]


def test_an_episode_failing_in_process_leaves_no_temporary_folder(tmp_path, monkeypatch):
    """In this process nothing else can still be writing: what is unlisted goes at once."""
    from testbed import generate as gen

    config, out = _prepared(tmp_path, 3)

    def episode(config, index, out, *args, **kwargs):
        if index == 1:
            (Path(out) / ".episode_0001.k2j3.tmp" / "masks").mkdir(parents=True)
            raise RuntimeError("episode 1 failed")
        return fake_episode(config, index, out)

    monkeypatch.setattr(gen, "render_episode", episode)
    with pytest.raises(RuntimeError, match="episode 1 failed"):
        gen.generate(config, 3, out, {})
    assert sorted(p.name for p in out.iterdir()) == ["episode_0000", "manifest.json", "run_info.json"]


def test_the_lock_and_run_info_do_not_hide_the_error_that_stopped_a_run(tmp_path, monkeypatch):
    from testbed.generate import exclusive

    out = tmp_path / "ds"
    out.mkdir()
    real_unlink = os.unlink

    def lost_mount(path, *args, **kwargs):
        if str(path).endswith(".camtask-render.lock"):
            raise PermissionError(1, "Operation not permitted")
        return real_unlink(path, *args, **kwargs)

    monkeypatch.setattr(os, "unlink", lost_mount)
    with pytest.raises(RuntimeError, match="the real error"), exclusive(out):
        raise RuntimeError("the real error")


def test_a_write_probe_left_by_a_killed_run_is_not_content(tmp_path, monkeypatch):
    import pathlib

    from testbed.generate import check_out

    out = tmp_path / "ds"
    with monkeypatch.context() as m:
        m.setattr(pathlib.Path, "unlink", lambda self, missing_ok=False: None)    # killed before removing it
        check_out(out)
    assert len(list(out.iterdir())) == 1                    # the probe it wrote is still there
    assert check_out(out) == out                            # and is not content: no "not empty"
    assert check_out(out, resume=True) == out               # nor "not a camtask render dataset"


def test_run_info_that_cannot_be_written_does_not_hide_the_error_that_stopped_the_run(tmp_path, monkeypatch):
    from testbed import generate as gen

    config, out = _prepared(tmp_path, 2)

    def full(*args, **kwargs):
        raise OSError("cannot write DIR/.episode_0000.x.tmp/frames/cam02/000000.png: No space left on device")

    def run_info(path, data):
        raise OSError(f"cannot write {path}: No space left on device")

    monkeypatch.setattr(gen, "render_episode", full)
    monkeypatch.setattr(gen, "write_json_atomic", run_info)
    with pytest.raises(OSError, match="000000.png: No space"):
        gen.generate(config, 2, out, {})


def test_overwrite_refuses_a_folder_whose_manifest_json_is_not_ours(tmp_path, capsys):
    """A web extension or PWA has a manifest.json too: --overwrite must not empty it."""
    out = tmp_path / "extension"
    (out / "src").mkdir(parents=True)
    (out / "manifest.json").write_text('{"manifest_version": 3, "name": "mine"}')
    (out / "src" / "background.js").write_text("x")
    code, line = run(capsys, "lab", "--out", str(out), "--workers", "0", "--overwrite", "--frames", "1",
                     "--cameras", "1")
    assert code == 2 and "is not a camtask render dataset" in line
    assert (out / "src" / "background.js").read_text() == "x"


def test_overwrite_refuses_a_dataset_that_holds_the_runs_scene(tmp_path, capsys):
    from scene import scene_path

    out = tmp_path / "ds"
    assert main(["render", "lab", "--out", str(out), "--workers", "0", "--frames", "1", "--cameras", "1"]) == 0
    scene = out / "myscene.yaml"
    scene.write_text(scene_path("lab").read_text())
    code, line = run(capsys, str(scene), "--out", str(out), "--workers", "0", "--overwrite", "--frames", "1",
                     "--cameras", "1")
    assert code == 2 and "--overwrite empties" in line
    assert scene.is_file() and (out / "episode_0000").is_dir()


def test_overwrite_without_room_keeps_the_old_dataset(tmp_path, capsys, monkeypatch):
    import shutil
    from collections import namedtuple

    out = tmp_path / "ds"
    assert main(["render", "lab", "--out", str(out), "--workers", "0", "--frames", "1", "--cameras", "1"]) == 0
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(10**9, 10**9, 1000))
    code, line = run(capsys, "lab", "--out", str(out), "--workers", "0", "--overwrite", "--frames", "3")
    assert code == 2 and "one episode" in line
    assert (out / "episode_0000").is_dir()            # refused before anything was deleted


@pytest.mark.parametrize(("address", "why"), [
    ("127.0.0.1", "missing port number"),
    ("http://127.0.0.1:8786", "protocol 'http'; expected tcp://, tls://, ws://, wss://"),
    # Dask's own words were "Can't instantiate abstract class UCXConnector" (a protocol without ucx-py)
    ("ucx://127.0.0.1:8786", "protocol 'ucx'; expected tcp://")])
def test_a_malformed_scheduler_address_says_why(tmp_path, capsys, address, why):
    code, line = run(capsys, "lab", "--out", str(tmp_path / "out"), "--scheduler", address)
    assert code == 2 and "cannot use the address" in line and why in line


@pytest.mark.render
def test_bad_input_found_once_started_leaves_out_as_it_was(tmp_path, capsys):
    """A camera in a corner looking out of the room is found by rendering its background, after
    the manifest is written: the run left manifest.json and run_info.json, and the same
    command with the scene fixed was refused as a non-empty --out."""
    from scene import scene_path

    scene = tmp_path / "corner.yaml"
    scene.write_text(scene_path("lab").read_text().replace("{number: 4, position: [5.467, 0.05, 2.2]",
                                                           "{number: 4, position: [0.0, 0.0, 2.2]"))
    out, mine = tmp_path / "new" / "ds", tmp_path / "mine"
    mine.mkdir()
    for folder in (out, mine):
        code, line = run(capsys, str(scene), "--frames", "1", "--cameras", "4", "--workers", "0", "--out", str(folder))
        assert code == 2 and line.startswith("camtask render: error: background: camera 4 sees all black")
    assert not (tmp_path / "new").exists() and list(mine.iterdir()) == []
    assert run(capsys, "lab", "--frames", "1", "--cameras", "4", "--workers", "0", "--out", str(mine))[0] == 0


def test_verify_names_links_to_nowhere_loops_and_fifos_without_reading_them(tmp_path):
    """A link to itself stopped verify with ELOOP; a FIFO or a dangling link went unreported."""
    from testbed.episodes import checksums
    from testbed.generate import episode_problems

    ep = tmp_path / "episode_0000"
    (ep / "masks").mkdir(parents=True)
    (ep / "people.csv").write_text("frame\n")
    (ep / "masks" / "a.png").write_bytes(b"png")
    entry = {"name": ep.name, "files": checksums(ep)}
    assert episode_problems(tmp_path, entry) == {"missing": [], "changed": [], "extra": []}
    (ep / "masks" / "loop").symlink_to("loop")
    (ep / "gone").symlink_to(tmp_path / "nowhere")
    os.mkfifo(ep / "fifo")                        # reading it would wait forever
    assert episode_problems(tmp_path, entry) == {"missing": [], "changed": [],
                                                 "extra": ["fifo", "gone", "masks/loop"]}


@pytest.mark.skipif(not os.path.exists("/proc/self/mem"), reason="needs Linux's /proc/self/mem")
def test_verify_names_a_file_it_cannot_read(tmp_path, capsys):
    """A read error (EIO from a failing disk) stopped verify with `[Errno 5] Input/output
    error`, naming no file."""
    import json

    from testbed.episodes import checksums

    ep = tmp_path / "episode_0000"
    ep.mkdir()
    (ep / "people.csv").write_text("frame\n")
    files = checksums(ep) | {"scanlines.npz": "0" * 64}
    (ep / "scanlines.npz").symlink_to("/proc/self/mem")     # opens; reading it at 0 is EIO
    entry = {"index": 0, "name": ep.name, "seed": 0, "spawn_key": [0], "frames": 1, "files": files}
    (tmp_path / "manifest.json").write_text(json.dumps({"format_version": 2, "episode_layout": 3,
                                                        "checksum": "blake3", "episodes_planned": 1,
                                                        "episodes": [entry]}))
    capsys.readouterr()
    assert main(["verify", str(tmp_path)]) == 1
    err = capsys.readouterr().err.strip().splitlines()[-1]
    assert err == f"camtask verify: error: cannot read {ep / 'scanlines.npz'}: Input/output error"


def test_verify_says_an_episode_that_is_a_file_is_not_a_folder(tmp_path, capsys):
    """A file where an episode's folder should be was called `folder missing`."""
    import json

    from testbed.episodes import checksums

    for n in (0, 1):
        ep = tmp_path / f"episode_{n:04d}"
        ep.mkdir()
        (ep / "people.csv").write_text("frame\n")
    entries = [{"index": n, "name": f"episode_{n:04d}", "seed": 0, "spawn_key": [n], "frames": 1,
                "files": checksums(tmp_path / f"episode_{n:04d}")} for n in (0, 1)]
    (tmp_path / "manifest.json").write_text(json.dumps({"format_version": 2, "episode_layout": 3,
                                                        "checksum": "blake3", "episodes_planned": 2,
                                                        "episodes": entries}))
    shutil.rmtree(tmp_path / "episode_0000")
    shutil.rmtree(tmp_path / "episode_0001")
    (tmp_path / "episode_0001").write_text("not an episode")
    capsys.readouterr()
    assert main(["verify", str(tmp_path)]) == 1
    lines = capsys.readouterr().out.splitlines()
    assert "episode_0000: folder missing (1 file listed)" in lines
    assert "episode_0001: a file, not a folder (1 file listed)" in lines


@pytest.mark.parametrize("kind", ["a file", "a link"])
def test_resume_refuses_a_file_where_an_episode_is_to_be_written(tmp_path, capsys, kind):
    """A file or link named episode_0001 (not a run's: kept) made --resume render, fail to
    rename the episode into place with `[Errno 20] Not a directory: PosixPath(...)`, and
    say that --resume finishes the run, which failed again."""
    out = tmp_path / "ds"
    argv = ["lab", "--episodes", "2", "--frames", "1", "--cameras", "2", "--workers", "0", "--out", str(out)]
    assert run(capsys, *argv)[0] == 0
    shutil.rmtree(out / "episode_0001")
    if kind == "a file":
        (out / "episode_0001").write_text("mine")
    else:
        (out / "episode_0001").symlink_to(tmp_path / "elsewhere")
    kept = (out / "episode_0000" / "meta.json").stat().st_mtime_ns
    code, line = run(capsys, *argv, "--resume")
    assert code == 2, line
    assert line == (f"camtask render: error: --resume: {out / 'episode_0001'} is {kind}, not an episode folder, "
                    "and episode 1 is to be written there: move it away")
    assert (out / "episode_0000" / "meta.json").stat().st_mtime_ns == kept
    assert os.path.lexists(out / "episode_0001") and not (out / "episode_0001").is_dir()
    (out / "episode_0001").unlink()
    assert run(capsys, *argv, "--resume")[0] == 0 and main(["verify", str(out)]) == 0


def test_episode_config_refuses_an_unknown_format():
    """fmt is checked when the config is made: render_episode knows only png and video."""
    from testbed.episodes import FORMATS, EpisodeConfig

    with pytest.raises(ValueError, match="fmt: unknown value 'jpg'; expected one of png, video"):
        EpisodeConfig("lab", None, None, 4, 1, "jpg")
    assert {EpisodeConfig("lab", None, None, 4, 1, f).fmt for f in FORMATS} == set(FORMATS)


class FakeFuture:
    """A Dask future of ``fn(*args)``, done at the second look, computed when asked for."""

    def __init__(self, fn, args):
        self.fn, self.args, self.polls = fn, args, 0

    def add_done_callback(self, callback):
        pass

    def done(self):
        self.polls += 1
        return self.polls > 1

    def result(self):
        return self.fn(*self.args)

    def cancel(self):
        pass


class FakeClient:
    """A cluster of two one-thread workers that computes each task in this process."""

    def __init__(self):
        self.submitted, self.most = [], 0

    def nthreads(self):
        return {"tcp://worker-1": 1, "tcp://worker-2": 1}

    def submit(self, fn, *args, pure, key):
        self.submitted.append(FakeFuture(fn, args))
        self.most = max(self.most, sum(not f.polls > 1 for f in self.submitted))
        return self.submitted[-1]


def fake_episode(config, index, out, seconds=None):
    """render_episode, minus the rendering: the (empty) episode folder and its entry."""
    (Path(out) / f"episode_{index:04d}").mkdir()
    return {"index": index, "name": f"episode_{index:04d}", "seed": config.seed, "spawn_key": [index],
            "frames": config.frames, "files": {}}


def test_dask_runs_keep_a_few_episodes_submitted_not_all(tmp_path, monkeypatch):
    """--episodes 200000 submitted at once slowed rendering tenfold; 10**12 filled the memory."""
    from testbed import generate as gen

    config, out = _prepared(tmp_path, 30)
    monkeypatch.setattr(gen, "render_episode", fake_episode)
    client = FakeClient()
    done = gen.generate(config, 30, out, {}, client)
    assert sorted(done) == list(range(30)) and len(client.submitted) == 30
    assert client.most == 4 == gen.in_flight(client)         # two per worker thread, at least 4


def test_an_episode_failing_on_dask_cancels_those_still_submitted(tmp_path, monkeypatch):
    """Episode 1 fails while 2 and 3 are submitted: the run stops and cancels their futures
    (and the failed one's) rather than leave them to render on the cluster; 4 and 5 are
    never submitted."""
    from testbed import generate as gen

    cancelled = []

    class Future(FakeFuture):
        def cancel(self):
            cancelled.append(self.args[1])

    class Client(FakeClient):
        def submit(self, fn, *args, pure, key):
            self.submitted.append(Future(fn, args))
            return self.submitted[-1]

    def episode(config, index, out, *args, **kwargs):
        if index == 1:
            raise RuntimeError("episode 1 failed")
        return fake_episode(config, index, out)

    config, out = _prepared(tmp_path, 6)
    monkeypatch.setattr(gen, "render_episode", episode)
    client = Client()
    with pytest.raises(RuntimeError, match="episode 1 failed"):
        gen.generate(config, 6, out, {}, client)
    assert [f.args[1] for f in client.submitted] == [0, 1, 2, 3]
    assert sorted(cancelled) == [1, 2, 3]


def test_a_cluster_that_loses_every_worker_says_so_once(tmp_path, monkeypatch, capsys):
    """An existing cluster whose workers all went (a batch system's time limit, the whole
    `dask worker` killed) left the run waiting without a word, its progress bar still."""
    from testbed import generate as gen

    class Client(FakeClient):
        scheduler = type("Rpc", (), {"address": "tcp://10.0.0.5:8786"})

        def __init__(self, workers):
            super().__init__()
            self.workers = list(workers)        # True: the cluster has its workers at that look

        def nthreads(self):                     # the last look holds from then on
            return super().nthreads() if (self.workers.pop(0) if len(self.workers) > 1 else self.workers[0]) else {}

    config, out = _prepared(tmp_path, 10)
    monkeypatch.setattr(gen, "render_episode", fake_episode)
    capsys.readouterr()
    done = gen.generate(config, 10, out, {}, Client([True, False, False, True, False, True, True]))
    assert sorted(done) == list(range(10))
    warning = "warning: no Dask worker is left in the cluster at tcp://10.0.0.5:8786; {} episodes wait for one " \
              "(Ctrl-C stops)"
    assert capsys.readouterr().err.splitlines() == [warning.format(4), warning.format(2)]   # once per time

    class LocalClient(Client):                  # a local cluster's nanny restarts a dead worker in ~2 s
        cluster = object()

    out = tmp_path / "local"
    gen.prepare_output(out, config, 10, False, False)
    capsys.readouterr()
    assert sorted(gen.generate(config, 10, out, {}, LocalClient([True, False, False, True, True, True]))) == list(
        range(10))
    assert capsys.readouterr().err == ""        # it said "no Dask worker is left" on every restart


def test_an_episode_written_where_this_machine_does_not_see_it_is_not_listed(tmp_path, monkeypatch, capsys):
    """A worker that joins an existing cluster after the check that every worker shares --out
    (an adaptive cluster adding nodes, each with its own /scratch) wrote its episodes to its
    own disk: they were listed in the manifest, the run said "wrote 30 episodes (30/30
    finished)", exit 0, and `camtask verify` found the folders missing. Now the run stops
    in one line at the first such episode, which stays unlisted."""
    from pipeline import load_params
    from testbed import generate as gen
    from testbed.commands.render import machine_error
    from testbed.episodes import EpisodeConfig

    config = EpisodeConfig("lab", None, (2, 7), 1, 1, "png", load_params().to_dict())
    out = tmp_path / "data"
    elsewhere = tmp_path / "another machine" / "data"
    elsewhere.mkdir(parents=True)
    gen.prepare_output(out, config, 6, False, False)

    def episode(config, index, out, seconds=None):       # episode 3 goes to the worker that joined late
        return fake_episode(config, index, elsewhere if index == 3 else out, seconds)

    monkeypatch.setattr(gen, "render_episode", episode)
    monkeypatch.setattr(gen, "SHARE_PATIENCE", 0.3)
    with pytest.raises(gen.NotShared) as err:
        gen.generate(config, 6, out, {}, FakeClient())
    host = socket.gethostname()
    assert str(err.value) == (f"episode 3: a worker on {host} wrote it where this machine does not see it "
                              f"(no {out.absolute() / 'episode_0003'} here after 0.3 s); --out must be a folder "
                              "that every worker shares, at the same path (a worker that joined the cluster "
                              "after the run started?)")
    assert machine_error(err.value) == str(err.value)          # one line, the finished episodes named after it
    listed = [e["index"] for e in json.loads((out / "manifest.json").read_text())["episodes"]]
    assert 3 not in listed and listed == sorted(listed) and all((out / f"episode_{i:04d}").is_dir() for i in listed)


def test_an_episode_folder_that_shows_a_little_late_here_is_waited_for(tmp_path, monkeypatch):
    """A network file system may show a worker's renamed folder to this machine later."""
    from testbed import generate as gen

    naps = []

    def sleep(seconds):
        naps.append(seconds)
        if len(naps) == 3:
            (tmp_path / "episode_0002").mkdir()

    monkeypatch.setattr(gen.time, "sleep", sleep)
    gen.check_written_here(tmp_path, {"index": 2, "name": "episode_0002"}, "node7")
    assert len(naps) == 3


def test_params_that_cannot_give_a_picture_are_refused_before_any_work(tmp_path, capsys):
    """Every scanline would be empty: refused in one line before DIR is made, not in the episode."""
    params = tmp_path / "p.yaml"
    params.write_text("column_threshold: 100000\n")
    out = tmp_path / "data"
    code, line = run(capsys, "lab", "--out", str(out), "--workers", "0", "--frames", "1", "--cameras", "1",
                     "--params", str(params))
    assert code == 2 and "--params: column_threshold 100000 is not below the 552 pixels of a rectified column" in line
    assert not out.exists()


def test_overwrite_stopped_while_it_deletes_can_be_overwritten_again(tmp_path, capsys, monkeypatch):
    """Ctrl-C while --overwrite deleted a large dataset (it takes a while) could leave episodes
    without their manifest.json: --overwrite and --resume then refused the folder as not a
    dataset. The manifest goes last."""
    import json
    import shutil

    from testbed import generate

    out = tmp_path / "data"
    out.mkdir()
    names = [f"episode_{i:04d}" for i in range(6)]
    for name in names:
        (out / name).mkdir()
        (out / name / "meta.json").write_text("{}")
    (out / "manifest.json").write_text(json.dumps({"episodes": [], "episodes_planned": 6}))
    removed = []
    real_rmtree = shutil.rmtree

    def rmtree(path, *args, **kwargs):
        real_rmtree(path, *args, **kwargs)
        removed.append(os.path.basename(path))
        if len(removed) == 2:
            raise KeyboardInterrupt                  # Ctrl-C halfway through

    monkeypatch.setattr(generate.shutil, "rmtree", rmtree)
    listing = generate.Path.iterdir                  # a folder's order is the file system's: manifest first
    monkeypatch.setattr(generate.Path, "iterdir",
                        lambda self: iter(sorted(listing(self), key=lambda p: p.name != "manifest.json")))
    assert main(["render", "lab", "--out", str(out), "--workers", "0", "--overwrite", "--frames", "1"]) == 130
    monkeypatch.setattr(generate.shutil, "rmtree", real_rmtree)
    assert (out / "manifest.json").is_file()
    code, line = run(capsys, "lab", "--out", str(out), "--workers", "0", "--overwrite", "--frames", "1",
                     "--cameras", "2")
    assert code == 0, line
    assert sorted(p.name for p in out.iterdir()) == ["episode_0000", "manifest.json", "run_info.json"]


def test_overwrite_keeps_the_old_dataset_until_the_local_workers_are_up(tmp_path, capsys, monkeypatch):
    """--overwrite deleted the old episodes first, then started the local cluster: a cluster
    that failed to start (memory, ports) left the user with neither dataset."""
    import testbed.parallel

    out = tmp_path / "ds"
    assert main(["render", "lab", "--out", str(out), "--workers", "0", "--frames", "1", "--cameras", "1"]) == 0

    def no_cluster(*args, **kwargs):
        raise OSError("the local cluster did not start")

    monkeypatch.setattr(testbed.parallel, "open_client", no_cluster)
    code, line = run(capsys, "lab", "--out", str(out), "--workers", "2", "--episodes", "2", "--frames", "1",
                     "--cameras", "1", "--overwrite")
    assert code != 0 and line == "camtask render: error: the local cluster did not start"
    assert (out / "episode_0000").is_dir() and (out / "manifest.json").is_file()


def test_a_file_that_cannot_be_read_keeps_its_errno(tmp_path):
    """file_digest names the file it cannot read; its error kept the kind but lost the errno."""
    import errno

    from testbed.checksum import file_digest

    with pytest.raises(FileNotFoundError) as err:
        file_digest(tmp_path / "gone.png")
    assert err.value.errno == errno.ENOENT and str(err.value).startswith(f"cannot read {tmp_path / 'gone.png'}: ")


def test_an_out_that_is_a_file_is_refused_and_kept(tmp_path, capsys):
    (tmp_path / "ds").write_text("mine")
    for extra in ([], ["--resume"], ["--overwrite"]):
        code, line = run(capsys, "lab", "--frames", "1", "--out", str(tmp_path / "ds"), "--workers", "0", *extra)
        assert (code, line) == (2, f"camtask render: error: --out: {tmp_path / 'ds'} exists and is not a directory")
    assert (tmp_path / "ds").read_text() == "mine"


def test_resume_and_overwrite_together_are_refused(tmp_path, capsys):
    from testbed.generate import check_out

    with pytest.raises(SystemExit) as stop:             # the command line: argparse's exclusive group
        main(["render", "lab", "--out", str(tmp_path / "ds"), "--resume", "--overwrite"])
    assert stop.value.code == 2
    assert capsys.readouterr().err.splitlines()[-1] == ("camtask render: error: argument --overwrite: not allowed "
                                                        "with argument --resume")
    with pytest.raises(ValueError, match=r"^--resume and --overwrite: expected at most one of them$"):
        check_out(tmp_path / "ds", resume=True, overwrite=True)
    assert list(tmp_path.iterdir()) == []


def test_a_run_that_stopped_on_bad_input_forgets_only_a_manifest_of_no_episodes(tmp_path):
    from testbed.commands.render import forget_run

    (tmp_path / "manifest.json").write_text("not json {")   # not one of ours: kept, not deleted
    forget_run(tmp_path)
    assert (tmp_path / "manifest.json").read_text() == "not json {"
    forget_run(tmp_path / "none")                           # no manifest at all
    assert not (tmp_path / "none").exists()


def test_video_on_an_existing_cluster_checks_its_workers_ffmpeg_and_png_does_not(tmp_path, capsys, monkeypatch):
    import contextlib

    from testbed import generate, parallel

    @contextlib.contextmanager
    def client(workers, scheduler):
        yield object()

    def no_ffmpeg(client):
        raise ValueError("--scheduler: worker tcp://10.0.0.1:1 cannot write --format video (no ffmpeg)")

    def rendering(*args, **kwargs):
        raise ValueError("rendering started")

    monkeypatch.setattr(parallel, "open_client", client)
    monkeypatch.setattr(parallel, "wait_for_a_worker", lambda client, scheduler: None)
    monkeypatch.setattr(generate, "check_worker_versions", lambda client: None)
    monkeypatch.setattr(generate, "check_workers_share", lambda client, out: None)
    monkeypatch.setattr(generate, "check_workers_ffmpeg", no_ffmpeg)
    monkeypatch.setattr(generate, "generate", rendering)
    for fmt, message in (("video", "--scheduler: worker tcp://10.0.0.1:1 cannot write --format video (no ffmpeg)"),
                         ("png", "rendering started")):
        out = tmp_path / fmt / "ds"
        code, line = run(capsys, "lab", "--frames", "1", "--format", fmt, "--out", str(out),
                         "--scheduler", "tcp://10.0.0.5:8786")
        assert (code, line) == (2, f"camtask render: error: {message}")
        assert not (tmp_path / fmt).exists()


def test_machine_errors_of_a_run_on_an_existing_cluster_are_one_line():
    from distributed import KilledWorker

    from testbed.commands.render import machine_error

    full = OSError(28, "No space left on device")
    assert machine_error(full, "tcp://10.0.0.5:8786") == "[Errno 28] No space left on device"
    assert machine_error(ValueError("a bug"), "tcp://10.0.0.5:8786") is None
    worker = type("Worker", (), {"address": "tcp://10.0.0.7:4000"})()
    for failures, processes in ((0, "1 worker process"), (2, "3 worker processes")):
        died = KilledWorker("episode-0003", worker, allowed_failures=failures)
        assert machine_error(died) == (f"episode 3: {processes} died running it (the last at tcp://10.0.0.7:4000; "
                                       "out of memory?)")


def test_machine_error_imports_no_dask_when_no_cluster_was_used():
    import subprocess
    import sys

    code = ("import sys; from testbed.commands.render import machine_error; "
            "print(machine_error(ValueError('x')), 'distributed' in sys.modules)")
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True,
                          env={**os.environ, "PYTHONPATH": str(Path(__file__).parents[1])})
    assert done.stdout.split() == ["None", "False"]


def test_video_without_an_ffmpeg_is_refused_before_any_work(tmp_path, capsys, monkeypatch):
    monkeypatch.setenv("IMAGEIO_FFMPEG_EXE", str(tmp_path / "no-ffmpeg"))
    code, line = run(capsys, "lab", "--frames", "1", "--format", "video", "--out", str(tmp_path / "ds"),
                     "--workers", "0")
    assert (code, line) == (1, (f"camtask render: error: ffmpeg: '{tmp_path / 'no-ffmpeg'}' (IMAGEIO_FFMPEG_EXE) is "
                               "not an executable file; install imageio-ffmpeg's binaries or point "
                               "IMAGEIO_FFMPEG_EXE at an ffmpeg"))
    assert not (tmp_path / "ds").exists()


def test_a_manifest_that_lists_episodes_is_not_forgotten(tmp_path):
    from testbed.commands.render import forget_run
    from tests.test_tune_verify import dataset

    root = dataset(tmp_path / "ds", 1)
    before = (root / "manifest.json").read_text()
    forget_run(root)
    assert (root / "manifest.json").read_text() == before


def test_overwrite_refuses_a_dataset_that_holds_the_runs_params_deeper_down(tmp_path, capsys):
    from pipeline import load_params
    from testbed.episodes import EpisodeConfig
    from testbed.generate import prepare_output

    out = tmp_path / "ds"
    prepare_output(out, EpisodeConfig("lab", None, (1,), 1, 0, "png", load_params().to_dict()), 1, False, False)
    (out / "notes").mkdir()
    (out / "notes" / "p.yaml").write_text("column_threshold: 3.0\n")
    code, line = run(capsys, "lab", "--out", str(out), "--workers", "0", "--overwrite", "--frames", "1",
                     "--params", str(out / "notes" / "p.yaml"))
    assert (code, line) == (2, (f"camtask render: error: --overwrite: --params {out / 'notes' / 'p.yaml'} lies in "
                               f"{out}, which --overwrite empties; move it out of the dataset first"))
    assert (out / "notes" / "p.yaml").is_file()


def test_bad_input_found_once_a_resumed_run_started_keeps_its_manifest(tmp_path, capsys, monkeypatch):
    """Only a new run's manifest of no episodes is forgotten: --resume's was there before."""
    from testbed import generate

    out = tmp_path / "ds"
    argv = ("lab", "--frames", "1", "--cameras", "1", "--episodes", "2", "--out", str(out), "--workers", "0")

    def bad_input(*args, **kwargs):
        raise ValueError("background: black")
    monkeypatch.setattr(generate, "generate", bad_input)
    assert run(capsys, *argv) == (2, "camtask render: error: background: black")
    assert not out.exists()                                  # a new run: nothing left
    out.mkdir()
    from pipeline import load_params
    from testbed.episodes import EpisodeConfig

    config = EpisodeConfig("lab", None, (1,), 1, 0, "png", load_params().to_dict())
    generate.prepare_output(out, config, 2, False, False)    # a run stopped before its first episode
    before = {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()}
    assert generate.MANIFEST in before
    assert run(capsys, *argv, "--resume") == (2, "camtask render: error: background: black")
    assert {p.name: p.read_bytes() for p in out.iterdir() if p.is_file()} == before


def test_one_default_worker_renders_in_this_process(tmp_path, capsys, monkeypatch):
    """On a machine of one core, no cluster of one worker is started for two episodes."""
    import contextlib

    from testbed import parallel

    seen = []

    @contextlib.contextmanager
    def client(workers, scheduler):
        seen.append(workers)
        raise ValueError("no cluster here")
        yield
    monkeypatch.setattr(parallel, "default_workers", lambda: 1)
    monkeypatch.setattr(parallel, "open_client", client)
    assert run(capsys, "lab", "--frames", "1", "--episodes", "2", "--out", str(tmp_path / "ds"))[0] == 2
    assert seen == [0]


def test_a_scene_of_floor_plane_cameras_is_refused_before_any_work(tmp_path, capsys):
    code, line = run(capsys, "circle", "--frames", "1", "--out", str(tmp_path / "ds"), "--workers", "0")
    assert (code, line) == (2, ("camtask render: error: scene: 'circle' has floor-plane cameras only; rendering needs "
                               "calibrated cameras (the circular simulation is `camtask study cameras`, `static`, "
                               "`moving`, `tracking`)"))
    assert not (tmp_path / "ds").exists()


def test_overwrite_counts_what_it_deletes_as_free(tmp_path, capsys, monkeypatch):
    """1.5 MB free and 2 MB of an old dataset to delete: room for an episode of 3 MB."""
    from pipeline import load_params
    from testbed import generate
    from testbed.episodes import EpisodeConfig

    out = tmp_path / "ds"
    generate.prepare_output(out, EpisodeConfig("lab", None, (1,), 1, 0, "png", load_params().to_dict()), 1,
                            False, False)
    (out / "episode_0000").mkdir()
    (out / "episode_0000" / "old.bin").write_bytes(b"\1" * 2_000_000)
    looks = []

    def free_bytes(path):
        looks.append(path)
        return (1_500_000 if len(looks) == 1 else 10**10), "/fake"

    def rendering(*args, **kwargs):
        raise ValueError("rendering started")
    monkeypatch.setattr(generate, "estimate_bytes", lambda config, scene, episodes: 3_000_000 * episodes)
    monkeypatch.setattr(generate, "free_bytes", free_bytes)
    monkeypatch.setattr(generate, "generate", rendering)
    assert run(capsys, "lab", "--frames", "1", "--cameras", "1", "--out", str(out), "--workers", "0",
               "--overwrite") == (2, "camtask render: error: rendering started")


def test_the_column_threshold_is_checked_against_the_cameras_rendered(tmp_path, capsys):
    """Camera 2 pitched down to 35 degrees has a taller rectified column (790 rows) than
    camera 1 (552): --cameras 1 is held to camera 1's."""
    import yaml

    from scene import scene_path

    config = yaml.safe_load(scene_path("lab").read_text())
    config["cameras"]["poses"][1]["pitch_deg"] = 35.0
    (tmp_path / "scene.yaml").write_text(yaml.safe_dump(config))
    (tmp_path / "p.yaml").write_text("column_threshold: 600\n")
    code, line = run(capsys, str(tmp_path / "scene.yaml"), "--cameras", "1", "--frames", "1", "--params",
                     str(tmp_path / "p.yaml"), "--out", str(tmp_path / "ds"), "--workers", "0")
    assert (code, line) == (2, ("camtask render: error: --params: column_threshold 600 "
                               "is not below the 552 pixels of a rectified column; every scanline would be empty"))
    assert not (tmp_path / "ds").exists()


@pytest.mark.parametrize(("top", "entry", "problem"), [
    ({"episodes_planned": 0, "episode_layout": 1}, {}, None),                # the least of each is fine
    ({"episodes_planned": -1}, {}, "episodes_planned is -1, expected an integer >= 0"),
    ({"episode_layout": 0}, {}, "episode_layout is 0, expected an integer >= 1"),
    ({"episodes_planned": True}, {}, "episodes_planned is True, expected an integer >= 0"),
    ({}, {"index": False}, "episodes[0] lacks an integer index and frames, a name or a files mapping"),
    ({}, {"frames": True}, "episodes[0] lacks an integer index and frames, a name or a files mapping"),
])
def test_a_manifests_counts_are_integers_from_their_least(tmp_path, top, entry, problem):
    """JSON's true and false are no counts (Python takes them for 1 and 0), and the least
    planned count (0) and layout (1) are manifests of their own."""
    from testbed.generate import read_manifest

    first = {"index": 0, "name": "episode_0000", "frames": 2, "files": {}} | entry
    m = {"episodes": [first]} | top
    (tmp_path / "manifest.json").write_text(json.dumps(m))
    if problem is None:
        assert read_manifest(tmp_path) == m
    else:
        with pytest.raises(ValueError) as err:
            read_manifest(tmp_path)
        assert str(err.value) == f"cannot read {tmp_path / 'manifest.json'} (not a camtask manifest: {problem})"


def test_a_manifest_of_an_earlier_layout_that_lists_no_episode_is_resumed(tmp_path):
    """A run stopped before its first episode has no episodes of another layout to mix in."""
    from pipeline import load_params
    from testbed.episodes import EpisodeConfig
    from testbed.generate import EPISODE_LAYOUT, prepare_output, read_manifest

    config = EpisodeConfig("lab", None, (2,), 1, 0, "png", load_params().to_dict())
    out = tmp_path / "ds"
    prepare_output(out, config, 2, False, False)
    m = read_manifest(out)
    (out / "manifest.json").write_text(json.dumps(m | {"episode_layout": EPISODE_LAYOUT - 1}))
    assert prepare_output(out, config, 2, True, False) == {}
    assert read_manifest(out) == m                  # rewritten as this camtask's
    listed = {"index": 0, "name": "episode_0000", "frames": 1, "files": {}}
    (out / "manifest.json").write_text(json.dumps(m | {"episode_layout": EPISODE_LAYOUT - 1,
                                                       "episodes": [listed]}))
    with pytest.raises(ValueError, match=f"are of layout {EPISODE_LAYOUT - 1} \\(an earlier camtask\\)"):
        prepare_output(out, config, 2, True, False)


def test_problems_text_names_only_the_kinds_of_problem_found():
    from testbed.generate import problems_text

    problems = {"missing": [], "changed": ["b.png", "c.png"], "extra": ["d", "e", "f", "g"]}
    assert problems_text(problems) == "2 changed (b.png, c.png); 4 extra (d, e, f and 1 more)"
    assert problems_text({"missing": [], "changed": [], "extra": []}) == ""


@pytest.mark.timeout(60)
def test_resume_with_very_many_episodes_checks_the_folders_names_not_every_episodes(tmp_path):
    """--resume --episodes 10**9 looked for a file named as each episode still to render
    (~15 s a million here) before any work; the folder's own names are what can be in the way."""
    from testbed.generate import check_episode_names_free

    (tmp_path / "episode_0000").mkdir()
    for name in ("episode_00003", "episode_best.yaml", "notes.txt"):     # not an episode's name
        (tmp_path / name).write_text("mine")
    check_episode_names_free(tmp_path, {0: {}}, 10**12)
    (tmp_path / "episode_12345").write_text("mine")
    (tmp_path / "episode_0021").symlink_to(tmp_path / "notes.txt")
    check_episode_names_free(tmp_path, {0: {}}, 21)     # both beyond the episodes to render
    with pytest.raises(FileExistsError) as err:
        check_episode_names_free(tmp_path, {0: {}}, 10**12)
    assert str(err.value) == (f"--resume: {tmp_path / 'episode_0021'} is a link, not an episode folder, and "
                              "episode 21 is to be written there: move it away")
    check_episode_names_free(tmp_path, {0: {}, 21: {}, 12345: {}}, 10**12)
    with pytest.raises(FileExistsError, match="episode_12345 is a file, not an episode folder, and episode 12345"):
        check_episode_names_free(tmp_path, {0: {}, 21: {}}, 10**12)


def test_exactly_the_room_needed_is_enough(tmp_path, monkeypatch):
    import collections

    from testbed import generate

    usage = collections.namedtuple("usage", "total used free")
    monkeypatch.setattr(generate.shutil, "disk_usage", lambda path: usage(10**12, 0, 7_000_000))
    generate.check_space(tmp_path, 7_000_000, "one episode")
    generate.check_space(tmp_path, 9_000_000, "one episode", freed=2_000_000)
    with pytest.raises(ValueError) as err:
        generate.check_space(tmp_path, 9_000_001, "one episode", freed=2_000_000)
    assert str(err.value) == (f"--out: 7 MB free on {tmp_path} (and 2 MB that --overwrite would free); "
                              "one episode needs about 9 MB")


def test_the_space_of_an_out_not_yet_made_is_its_nearest_existing_parents(tmp_path):
    from testbed.generate import check_space

    with pytest.raises(ValueError) as err:
        check_space(tmp_path / "new" / "ds", 10**18, "the run")
    assert f" free on {tmp_path}; the run needs about 1e+06 TB" in str(err.value)
    assert not (tmp_path / "new").exists()


@pytest.mark.parametrize(("n", "text"), [
    (1e9, "1 GB"), (999_600_000, "1 GB"), (999_400_000, "999 MB"), (1_500_000, "1.5 MB"),
    (1.5e12, "1.5 TB"), (999.7e9, "1 TB"), (12_345_678_901, "12.3 GB")])
def test_sizes_are_three_digits_without_an_exponent(n, text):
    """A disk of 1.5 TB free was "1.5e+03 GB free", 999.6 MB "1e+03 MB" (three significant
    digits of 1000 or more)."""
    from testbed.generate import size_text

    assert size_text(n) == text


def test_frames_in_progress_counts_the_first_cameras_masks_of_each_temporary_episode(tmp_path):
    from testbed.generate import frames_in_progress

    def frames(folder, cams):
        for cam, n in cams.items():
            (tmp_path / folder / "masks" / cam).mkdir(parents=True)
            for f in range(n):
                (tmp_path / folder / "masks" / cam / f"{f:06d}.png").write_bytes(b"")

    frames(".episode_0003.a1b2.tmp", {"cam02": 4, "cam05": 3, "cam11": 1})    # cam02 runs ahead
    frames(".episode_0012.c3.tmp", {"cam01": 2})
    frames(".episode_0013.d4.tmp", {})                                        # no masks yet
    (tmp_path / ".episode_0014.e5.tmp").mkdir()                               # no masks folder yet
    frames("episode_0001", {"cam01": 9})                                      # finished: not in progress
    frames(".episode_x.f6.tmp", {"cam01": 9})                                 # not a run's
    assert frames_in_progress(tmp_path) == {3: 4, 12: 2}


@pytest.mark.parametrize("reverse", [False, True])
def test_frames_in_progress_of_an_episode_in_two_temporary_folders_are_the_most(tmp_path, monkeypatch, reverse):
    """A worker that died left its folder beside the next try's: the furthest on counts, found first or last."""
    import pathlib

    from testbed.generate import frames_in_progress

    for folder, n in ((".episode_0003.a1.tmp", 5), (".episode_0003.b2.tmp", 2)):
        (tmp_path / folder / "masks" / "cam01").mkdir(parents=True)
        for f in range(n):
            (tmp_path / folder / "masks" / "cam01" / f"{f:06d}.png").write_bytes(b"")
    real = pathlib.Path.glob
    monkeypatch.setattr(pathlib.Path, "glob", lambda self, pattern: iter(sorted(real(self, pattern),
                                                                                   reverse=reverse)))
    assert frames_in_progress(tmp_path) == {3: 5}


@pytest.mark.parametrize(("text", "runs"), [
    (None, []),
    ("{bad", []),
    ("[1, 2]", []),
    ('{"host": "c", "earlier_runs": [{"host": "a"}, {"host": "b"}]}', [{"host": "a"}, {"host": "b"}, {"host": "c"}]),
    ('{"host": "c", "earlier_runs": "lost"}', [{"host": "c"}]),
])
def test_earlier_runs_are_the_records_of_run_info_oldest_first(tmp_path, text, runs):
    from testbed.generate import earlier_runs

    if text is not None:
        (tmp_path / "run_info.json").write_text(text)
    assert earlier_runs(tmp_path) == runs


def test_version_changes_name_only_the_packages_that_make_the_bytes():
    from testbed.generate import version_changes

    a = {"python": "3.11.2", "numpy": "2.3.0", "dask": "1", "blake3": "1.0", "fpng": "0.1"}
    b = {"python": "3.12.0", "numpy": "2.4.6", "dask": "2", "blake3": "1.0", "isal": "1.7"}
    assert version_changes(a, b, "then", "now") == "fpng 0.1 then, None now, isal None then, 1.7 now, " \
                                                   "numpy 2.3.0 then, 2.4.6 now"
    assert version_changes(a, a | {"distributed": "9"}, "there", "here") == ""


def test_other_versions_are_those_of_the_last_run_not_the_first(tmp_path, monkeypatch, capsys):
    """A run with other versions, resumed with this one's: the last run's episodes are this one's bytes
    too, and the first run's (kept from then on) were compared when the last run resumed it."""
    from pipeline import load_params
    from testbed import generate as gen
    from testbed.episodes import EpisodeConfig

    config = EpisodeConfig("lab", None, (2,), 1, 1, "png", load_params().to_dict())
    monkeypatch.setattr(gen, "render_episode", lambda config, i, out, *args, **kw: fake_episode(config, i, out))
    out = tmp_path / "data"
    gen.prepare_output(out, config, 2, False, False)
    first = {"versions": gen.versions() | {"numpy": "1.0.0"}}
    (out / "run_info.json").write_text(json.dumps({"versions": gen.versions(), "earlier_runs": [first]}))
    capsys.readouterr()
    gen.generate(config, 2, out, {0: {"index": 0, "name": "episode_0000", "frames": 1}})
    assert "other package versions" not in capsys.readouterr().err


def test_in_flight_is_two_per_worker_thread_and_at_least_four():
    from testbed.generate import in_flight

    class Client:
        def __init__(self, threads):
            self.threads = threads

        def nthreads(self):
            return self.threads

    assert in_flight(Client({"a": 3, "b": 2})) == 10
    assert in_flight(Client({"a": 1})) == 4 == in_flight(Client({}))
    assert in_flight(Client({}), {"a": 4, "b": 4}) == 16        # the threads given win over a new look


def test_other_versions_are_a_warning_only_when_episodes_of_the_run_before_are_kept(tmp_path, monkeypatch, capsys):
    """A --resume that keeps no episode mixes nothing: no word of the versions before."""
    from pipeline import load_params
    from testbed import generate as gen
    from testbed.episodes import EpisodeConfig

    config = EpisodeConfig("lab", None, (2,), 1, 1, "png", load_params().to_dict())
    monkeypatch.setattr(gen, "render_episode", lambda config, i, out, *args, **kw: fake_episode(config, i, out))
    for keep, warned in (({}, False), ({0: {"index": 0, "name": "episode_0000", "frames": 1}}, True)):
        out = tmp_path / str(warned)
        gen.prepare_output(out, config, 2, False, False)
        (out / "run_info.json").write_text(json.dumps({"versions": gen.versions() | {"numpy": "1.0.0"}}))
        capsys.readouterr()
        gen.generate(config, 2, out, keep)
        err = capsys.readouterr().err
        assert ("warning: --resume: other package versions than the run before (numpy 1.0.0 then, " in err) == warned


def test_an_episode_failing_on_dask_leaves_the_folders_other_workers_may_still_write(tmp_path, monkeypatch):
    """Cancelled episodes may still be running: their temporary folders are the caller's to
    remove once the workers have stopped (remove_unlisted), not generate's."""
    from pipeline import load_params
    from testbed import generate as gen
    from testbed.episodes import EpisodeConfig

    def episode(config, index, out, seconds=None):
        if index == 1:
            raise RuntimeError("episode 1 failed")
        return fake_episode(config, index, out, seconds)

    config = EpisodeConfig("lab", None, (2,), 1, 1, "png", load_params().to_dict())
    out = tmp_path / "data"
    gen.prepare_output(out, config, 3, False, False)
    running = out / ".episode_0002.w7.tmp"                     # another worker's episode, being written
    running.mkdir()
    monkeypatch.setattr(gen, "render_episode", episode)
    with pytest.raises(RuntimeError, match="episode 1 failed"):
        gen.generate(config, 3, out, {}, FakeClient())
    assert running.is_dir()
    assert [e["index"] for e in gen.read_manifest(out)["episodes"]] == [0]


def test_run_info_keeps_each_episodes_stage_seconds_to_the_millisecond(tmp_path, monkeypatch):
    from pipeline import load_params
    from testbed import generate as gen
    from testbed.episodes import EpisodeConfig

    def episode(config, index, out, progress=None, seconds=None, overlap=False):
        seconds.update({"render": 1.23456, "png": 0.0004, "total": 2.0 + index})
        return fake_episode(config, index, out)

    config = EpisodeConfig("lab", None, (2,), 1, 1, "png", load_params().to_dict())
    out = tmp_path / "data"
    gen.prepare_output(out, config, 2, False, False)
    monkeypatch.setattr(gen, "render_episode", episode)
    assert sorted(gen.generate(config, 2, out, {})) == [0, 1]
    info = json.loads((out / "run_info.json").read_text())
    assert info["episode_seconds"] == {"episode_0000": {"png": 0.0, "render": 1.235, "total": 2.0},
                                       "episode_0001": {"png": 0.0, "render": 1.235, "total": 3.0}}
    assert info["episodes_done"] == 2 and list(info["episode_hosts"]) == ["episode_0000", "episode_0001"]


def test_run_info_counts_the_kept_episodes_as_done_and_names_the_hosts_of_those_rendered(tmp_path, monkeypatch):
    from pipeline import load_params
    from testbed import generate as gen
    from testbed.episodes import EpisodeConfig

    config = EpisodeConfig("lab", None, (2,), 1, 1, "png", load_params().to_dict())
    out = tmp_path / "data"
    gen.prepare_output(out, config, 3, False, False)
    monkeypatch.setattr(gen, "render_episode", lambda config, i, out, *args, **kw: fake_episode(config, i, out))
    kept = {1: {"index": 1, "name": "episode_0001", "frames": 1, "files": {}}}
    assert sorted(gen.generate(config, 3, out, kept)) == [0, 1, 2]
    info = json.loads((out / "run_info.json").read_text())
    assert info["episodes_done"] == 3 and list(info["episode_hosts"]) == ["episode_0000", "episode_0002"]


@pytest.mark.parametrize("next_run", [True, False])
def test_a_lock_file_its_holder_deleted_meanwhile_is_not_the_one_locked(tmp_path, monkeypatch, next_run):
    """A run that ends deletes its lock file: a run that opened the old file just before
    would hold a lock on a file no longer in the folder, which a third run would not see;
    it locks the file now at that name instead (the next run's, or a new one if none came)."""
    from testbed import generate

    real_flock = generate.fcntl.flock
    out = tmp_path / "ds"
    out.mkdir()
    calls = []

    def flock(fd, op):
        real_flock(fd, op)
        if not calls:                                 # the holder ends between our open and our lock
            (out / generate.LOCK).unlink()
            if next_run:
                (out / generate.LOCK).write_bytes(b"")   # and the next run's file takes the name
        calls.append(fd)

    monkeypatch.setattr(generate.fcntl, "flock", flock)
    fd = generate._lock(out / generate.LOCK, out)
    try:
        assert len(calls) == 2 and os.fstat(fd).st_ino == os.stat(out / generate.LOCK).st_ino
    finally:
        os.close(fd)


def test_a_file_system_that_cannot_lock_is_written_with_a_warning(tmp_path, monkeypatch, capsys):
    import errno

    from testbed import generate

    out = tmp_path / "ds"
    out.mkdir()

    def flock(fd, op):
        raise OSError(errno.ENOLCK, "No locks available")

    monkeypatch.setattr(generate.fcntl, "flock", flock)
    with generate.exclusive(out):
        (out / "manifest.json").write_text("{}")
    assert capsys.readouterr().err == (f"warning: --out: cannot lock {out / generate.LOCK} (No locks available): "
                                       f"a second run into {out} would not be refused\n")


def test_on_dask_an_episodes_last_frame_is_counted_once_it_is_listed(tmp_path, monkeypatch):
    """The bar counts the masks in a running episode's temporary folder, all but the last
    frame: an episode shows complete only when it is finished and listed."""
    from pipeline import load_params
    from testbed import generate as gen
    from testbed.episodes import EpisodeConfig

    config = EpisodeConfig("lab", None, (2,), 3, 1, "png", load_params().to_dict())
    out = tmp_path / "data"
    gen.prepare_output(out, config, 1, False, False)
    masks = out / ".episode_0000.w1.tmp" / "masks" / "cam02"
    masks.mkdir(parents=True)
    for f in range(3):                                  # every frame written, not yet renamed into place
        (masks / f"{f:06d}.png").write_bytes(b"")
    counted = []
    monkeypatch.setattr(gen, "render_episode", fake_episode)
    gen.generate(config, 1, out, {}, FakeClient(), progress=counted.append)
    assert counted == [2, 1]
