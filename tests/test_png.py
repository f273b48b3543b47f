"""The dataset PNG writer: standard PNGs that OpenCV decodes to the same pixels."""

import os
import stat

import blake3
import cv2
import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from testbed.png import encode_png, write_png


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 40), st.integers(1, 40), st.sampled_from(["rgb", "grey", "grey16"]),
       st.integers(0, 2**32 - 1))
def test_round_trip_through_opencv(h, w, kind, seed):
    rng = np.random.default_rng(seed)
    if kind == "rgb":
        img = rng.integers(0, 256, (h, w, 3), dtype=np.uint8)
    elif kind == "grey":
        img = rng.integers(0, 256, (h, w), dtype=np.uint8)
    else:
        img = rng.integers(0, 65536, (h, w), dtype=np.uint16)
    back = cv2.imdecode(np.frombuffer(encode_png(img), np.uint8), cv2.IMREAD_UNCHANGED)
    if kind == "rgb":
        back = cv2.cvtColor(back, cv2.COLOR_BGR2RGB)
    assert back.dtype == img.dtype
    assert np.array_equal(back, img)


def test_write_returns_the_files_blake3_and_bytes_repeat(tmp_path):
    img = np.random.default_rng(1).integers(0, 256, (48, 64, 3), dtype=np.uint8)
    digest = write_png(tmp_path / "a.png", img)
    assert digest == blake3.blake3((tmp_path / "a.png").read_bytes()).hexdigest()
    assert encode_png(img) == encode_png(img.copy())


@pytest.mark.parametrize("bad", [np.zeros((4, 4, 4), np.uint8), np.zeros((4, 4), np.float32),
                                 np.zeros((0, 4), np.uint8), np.zeros((4, 0), np.uint16), np.zeros((3, 0, 3), np.uint8),
                                 np.zeros(4, np.uint8)])
def test_bad_images_are_refused(bad):
    with pytest.raises(ValueError, match="image: expected"):
        encode_png(bad)


def test_unwritable_path_is_one_line(tmp_path):
    with pytest.raises(OSError, match="cannot write"):
        write_png(tmp_path / "missing" / "a.png", np.zeros((2, 2), np.uint8))


@settings(max_examples=30, deadline=None)
@given(st.integers(1, 40), st.integers(1, 40), st.booleans(), st.integers(0, 2**32 - 1))
def test_grey_pngs_are_the_chunks_of_the_sub_filter_and_isal(h, w, wide, seed):
    """Grey PNGs byte for byte: signature, IHDR, one IDAT of the SUB-filtered rows deflated by
    ISA-L at LEVEL, IEND (the header and end chunks are made once, not per image)."""
    import struct

    from isal import isal_zlib

    from testbed.png import LEVEL

    rng = np.random.default_rng(seed)
    img = rng.integers(0, 65536 if wide else 256, (h, w), dtype=np.uint16 if wide else np.uint8)
    rows = img.astype(">u2" if wide else np.uint8).view(np.uint8).reshape(h, -1)
    bpp = 2 if wide else 1
    sub = np.concatenate([np.ones((h, 1), np.uint8), rows[:, :bpp],
                          (rows[:, bpp:].astype(int) - rows[:, :-bpp]).astype(np.uint8)], axis=1)

    def chunk(kind, data):
        return struct.pack(">I", len(data)) + kind + data + struct.pack(">I", isal_zlib.crc32(kind + data))

    want = (b"\x89PNG\r\n\x1a\n" + chunk(b"IHDR", struct.pack(">IIBBBBB", w, h, 8 * bpp, 0, 0, 0, 0))
            + chunk(b"IDAT", isal_zlib.compress(sub.tobytes(), LEVEL)) + chunk(b"IEND", b""))
    assert encode_png(img) == want


def test_write_file_replaces_a_longer_file_whole(tmp_path):
    from testbed.png import write_file

    path = tmp_path / "a.png"
    path.write_bytes(b"x" * 100)
    write_file(str(path), memoryview(b"abc"))
    assert path.read_bytes() == b"abc"
    big = np.random.default_rng(2).integers(0, 256, 3 << 20, dtype=np.uint8).tobytes()
    write_file(path, big)
    assert path.read_bytes() == big


def test_short_writes_are_continued_where_they_stopped(tmp_path, monkeypatch):
    """os.write may write less than it is given (a signal, a network file system)."""
    from testbed.png import write_file

    data = np.random.default_rng(3).integers(0, 256, 10_000, dtype=np.uint8).tobytes()
    real = os.write
    with monkeypatch.context() as m:
        m.setattr(os, "write", lambda fd, view: real(fd, view[:999]))
        write_file(tmp_path / "a.bin", data)
    assert (tmp_path / "a.bin").read_bytes() == data


def test_files_get_the_permissions_the_umask_gives(tmp_path):
    old = os.umask(0o002)
    try:
        write_png(tmp_path / "a.png", np.zeros((2, 2), np.uint8))
    finally:
        os.umask(old)
    assert stat.S_IMODE((tmp_path / "a.png").stat().st_mode) == 0o664


@pytest.mark.parametrize("bad", [np.zeros((4, 4, 3), np.uint16), np.zeros((4, 4), np.int16),
                                 np.zeros((4, 4), np.uint32), np.zeros((4, 4), bool)])
def test_other_sample_types_are_refused_not_reinterpreted(bad):
    with pytest.raises(ValueError, match=rf"^image: expected .*, got \(4, 4.*\) {bad.dtype}$"):
        encode_png(bad)


def test_rgb_pngs_are_fpngs():
    """Colour goes through fpng (the fast path), not the grey images' SUB filter."""
    import fpng

    img = np.random.default_rng(4).integers(0, 256, (12, 20, 3), dtype=np.uint8)
    assert encode_png(img) == fpng.from_ndarray(img)


def test_strided_images_are_written_as_their_pixels():
    rng = np.random.default_rng(5)
    rgb = rng.integers(0, 256, (9, 14, 3), dtype=np.uint8)
    grey = rng.integers(0, 65536, (9, 14), dtype=np.uint16)
    for img in (rgb[:, ::2], rgb[..., ::-1], rgb.transpose(1, 0, 2), grey[::2, ::3], grey.T,
                grey.astype(np.uint8)[:, ::-1]):
        back = cv2.imdecode(np.frombuffer(encode_png(img), np.uint8), cv2.IMREAD_UNCHANGED)
        assert np.array_equal(back[..., ::-1] if img.ndim == 3 else back, img)


def test_a_flat_label_image_is_compressed():
    """One label over 640 x 480 pixels: a few hundred bytes, not the 300 KB of its samples."""
    assert len(encode_png(np.full((480, 640), 3, np.uint8))) < 3000


def test_a_failed_write_is_one_line_with_the_systems_reason_and_closes_the_file():
    from testbed.png import write_file

    if not os.path.exists("/dev/full"):
        pytest.skip("no /dev/full")
    before = len(os.listdir("/proc/self/fd"))
    with pytest.raises(OSError, match=r"^cannot write /dev/full: No space left on device$") as err:
        write_file("/dev/full", b"x" * 10)
    assert err.value.__suppress_context__
    assert len(os.listdir("/proc/self/fd")) == before
