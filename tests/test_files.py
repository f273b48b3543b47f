"""pipeline.files: whole files and folders, with the permissions the umask gives."""

import os
import stat
from pathlib import Path

import pytest

from pipeline.files import temp_folder, write_atomic


@pytest.fixture
def umask_027():
    old = os.umask(0o027)
    yield
    os.umask(old)


def mode(path):
    return stat.S_IMODE(path.stat().st_mode)


def test_write_atomic_replaces_the_file_with_umask_permissions(tmp_path, umask_027):
    path = tmp_path / "a.json"
    path.write_text("old")
    write_atomic(path, b"new")
    assert path.read_bytes() == b"new" and mode(path) == 0o640
    assert [p.name for p in tmp_path.iterdir()] == ["a.json"]


def test_write_atomic_leaves_the_old_file_when_writing_fails(tmp_path):
    path = tmp_path / "a.json"
    path.write_text("old")
    with pytest.raises(TypeError):
        write_atomic(path, "not bytes")
    assert path.read_text() == "old" and [p.name for p in tmp_path.iterdir()] == ["a.json"]


def test_temp_folder_is_new_empty_and_has_umask_permissions(tmp_path, umask_027):
    a, b = temp_folder(tmp_path, ".ep."), temp_folder(tmp_path, ".ep.")
    assert a != b and a.parent == tmp_path and a.name.startswith(".ep.") and a.name.endswith(".tmp")
    assert list(a.iterdir()) == [] and mode(a) == 0o750


def test_temp_folder_gives_up_with_a_clear_error(tmp_path, monkeypatch):
    monkeypatch.setattr("secrets.token_hex", lambda n: "same")
    temp_folder(tmp_path, "x.")
    with pytest.raises(FileExistsError, match=r"no unused temporary name x\.\*\.tmp in"):
        temp_folder(tmp_path, "x.")


def test_ctrl_c_just_after_the_temporary_file_is_made_leaves_none(tmp_path, monkeypatch):
    """A signal landing after os.open made the temporary file, before write_atomic held its
    name, left a .manifest.json.<random>.tmp behind, in which --overwrite then saw a folder
    that is not a dataset."""
    real = os.open

    def open_then_interrupted(*args, **kwargs):
        real(*args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(os, "open", open_then_interrupted)
    with pytest.raises(KeyboardInterrupt):
        write_atomic(tmp_path / "manifest.json", b"{}")
    monkeypatch.undo()
    assert list(tmp_path.iterdir()) == []


@pytest.fixture
def umask_0():
    old = os.umask(0)
    yield
    os.umask(old)


def test_without_a_umask_files_and_folders_are_open_to_all(tmp_path, umask_0):
    """As open and mkdir make them under umask 0: 0666 and 0777."""
    write_atomic(tmp_path / "a.json", b"x")
    assert mode(tmp_path / "a.json") == 0o666 and mode(temp_folder(tmp_path, "t.")) == 0o777


def test_a_taken_temporary_name_is_passed_over_and_left_as_it_was(tmp_path, monkeypatch):
    names = iter(["same", "next", "same", "other"])
    monkeypatch.setattr("secrets.token_hex", lambda n: next(names))
    (tmp_path / ".a.json.same.tmp").write_text("stray")
    (tmp_path / "x.same.tmp").mkdir()
    write_atomic(tmp_path / "a.json", b"new")
    assert temp_folder(tmp_path, "x.") == tmp_path / "x.other.tmp"
    assert (tmp_path / "a.json").read_bytes() == b"new" and (tmp_path / ".a.json.same.tmp").read_text() == "stray"
    assert sorted(p.name for p in tmp_path.iterdir()) == [".a.json.same.tmp", "a.json", "x.other.tmp", "x.same.tmp"]


def test_write_atomic_makes_the_missing_folders(tmp_path):
    write_atomic(tmp_path / "a" / "b" / "c.json", b"{}")
    assert (tmp_path / "a" / "b" / "c.json").read_bytes() == b"{}"
    assert os.listdir(tmp_path / "a" / "b") == ["c.json"]


def test_ctrl_c_just_after_the_temporary_folder_is_made_leaves_none(tmp_path, monkeypatch):
    real = Path.mkdir

    def mkdir_then_interrupted(self, *args, **kwargs):
        real(self, *args, **kwargs)
        raise KeyboardInterrupt

    monkeypatch.setattr(Path, "mkdir", mkdir_then_interrupted)
    with pytest.raises(KeyboardInterrupt):
        temp_folder(tmp_path, ".ep.")
    monkeypatch.undo()
    assert list(tmp_path.iterdir()) == []
