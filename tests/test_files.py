"""pipeline.files: whole files and folders, with the permissions the umask gives."""

import os
import stat

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
