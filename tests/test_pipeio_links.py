"""Output files given as symbolic links are written through, atomically beside the target."""

import errno
import os
import re

import numpy as np
import pytest

from pipeline.files import write_atomic
from pipeline.io import save_npz_atomic


@pytest.fixture
def link(tmp_path):
    """tmp/out/link.yaml -> ../data/real.yaml (relative, as `ln -s` makes them)."""
    (tmp_path / "data").mkdir()
    (tmp_path / "out").mkdir()
    (tmp_path / "data" / "real.yaml").write_text("old")
    os.symlink("../data/real.yaml", tmp_path / "out" / "link.yaml")
    return tmp_path / "out" / "link.yaml"


def test_write_atomic_writes_a_link_s_target_and_keeps_the_link(link, tmp_path):
    write_atomic(link, b"new")
    assert link.is_symlink() and os.readlink(link) == "../data/real.yaml"
    assert (tmp_path / "data" / "real.yaml").read_bytes() == b"new"
    assert sorted(os.listdir(tmp_path / "data")) == ["real.yaml"]       # no temporary left
    assert sorted(os.listdir(tmp_path / "out")) == ["link.yaml"]


def test_write_atomic_through_a_chain_and_a_dangling_link(tmp_path):
    os.symlink("b", tmp_path / "a")
    os.symlink("sub/c", tmp_path / "b")
    write_atomic(tmp_path / "a", b"made")               # as `echo made > a` does, its folder made
    assert (tmp_path / "a").is_symlink() and (tmp_path / "b").is_symlink()
    assert (tmp_path / "sub" / "c").read_bytes() == b"made"


def test_write_atomic_refuses_a_loop_of_links_in_one_line(tmp_path):
    os.symlink("b", tmp_path / "a")
    os.symlink("a", tmp_path / "b")
    with pytest.raises(OSError, match=r"^cannot write .*a: Too many levels of symbolic links$") as info:
        write_atomic(tmp_path / "a", b"x")
    assert info.value.errno == errno.ELOOP
    assert os.readlink(tmp_path / "a") == "b" and sorted(os.listdir(tmp_path)) == ["a", "b"]


def test_write_atomic_leaves_the_target_when_writing_fails(link, tmp_path):
    with pytest.raises(TypeError):
        write_atomic(link, "not bytes")
    assert (tmp_path / "data" / "real.yaml").read_text() == "old" and link.is_symlink()
    assert sorted(os.listdir(tmp_path / "data")) == ["real.yaml"]


def test_write_atomic_writes_a_hidden_temporary_beside_the_target(link, tmp_path):
    """In the target's folder, not the link's (a rename cannot cross file systems), and
    hidden from listings until it is renamed."""
    seen = []

    def pieces():
        yield b"ne"
        seen.append((sorted(os.listdir(tmp_path / "data")), os.listdir(tmp_path / "out")))
        yield b"w"

    write_atomic(link, pieces())
    (tmp, real), out = seen[0]
    assert re.fullmatch(r"\.real\.yaml\..+\.tmp", tmp) and real == "real.yaml" and out == ["link.yaml"]
    assert (tmp_path / "data" / "real.yaml").read_bytes() == b"new"


def test_a_full_disk_names_the_link_written_through(link, tmp_path, monkeypatch):
    """The path as given, as open(link, "w") names it, in one error not chained onto the one caught."""
    def full(src, dst):
        raise OSError(errno.ENOSPC, "No space left on device")

    monkeypatch.setattr(os, "replace", full)
    with pytest.raises(OSError) as info:
        write_atomic(link, b"new")
    assert str(info.value) == f"cannot write {link}: No space left on device"
    assert info.value.__cause__ is None and info.value.__suppress_context__
    assert (tmp_path / "data" / "real.yaml").read_text() == "old"
    assert sorted(os.listdir(tmp_path / "data")) == ["real.yaml"]


def test_save_npz_atomic_writes_a_link_s_target(tmp_path):
    (tmp_path / "data").mkdir()
    np.savez(tmp_path / "data" / "s.npz", a=np.zeros(1))
    os.symlink("data/s.npz", tmp_path / "s.npz")
    save_npz_atomic(tmp_path / "s.npz", a=np.arange(3))
    assert (tmp_path / "s.npz").is_symlink()
    with np.load(tmp_path / "data" / "s.npz") as z:
        assert z["a"].tolist() == [0, 1, 2]
    assert sorted(os.listdir(tmp_path / "data")) == ["s.npz"]


def test_save_npz_atomic_names_the_file_it_cannot_write(tmp_path, monkeypatch):
    def full(src, dst):
        raise OSError(28, "No space left on device")

    monkeypatch.setattr(os, "replace", full)
    with pytest.raises(OSError, match=r"^cannot write .*s.npz: No space left on device$"):
        save_npz_atomic(tmp_path / "s.npz", a=np.arange(3))
    assert os.listdir(tmp_path) == []


def test_save_npz_atomic_compresses_every_array(tmp_path):
    """Scanlines are long runs of equal bits: stored deflated, a 100 000-bit array is a few hundred bytes."""
    import zipfile

    bits = np.zeros((100, 16, 640), bool)
    bits[:, :, 100:140] = True
    save_npz_atomic(tmp_path / "s.npz", scanlines=bits, bearings=np.linspace(0, 1, 640))
    with zipfile.ZipFile(tmp_path / "s.npz") as z:
        assert {i.filename: i.compress_type for i in z.infolist()} == {
            "scanlines.npy": zipfile.ZIP_DEFLATED, "bearings.npy": zipfile.ZIP_DEFLATED}
    with np.load(tmp_path / "s.npz") as z:
        np.testing.assert_array_equal(z["scanlines"], bits)
    assert (tmp_path / "s.npz").stat().st_size < bits.size // 20
