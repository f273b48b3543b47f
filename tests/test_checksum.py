"""testbed.checksum: file digests equal the hash libraries' digests of the whole file."""

import hashlib

import blake3
import numpy as np
import pytest

from testbed.checksum import digest, file_digest


def test_a_file_of_several_blocks_is_hashed_whole_with_the_algorithm_asked(tmp_path):
    """2.5 MiB of random bytes: three 1 MiB reads, every one of them in the digest."""
    data = np.random.default_rng(0).bytes(5 << 19)
    path = tmp_path / "f.bin"
    path.write_bytes(data)
    assert file_digest(path) == blake3.blake3(data).hexdigest()
    assert file_digest(path, "sha256") == hashlib.sha256(data).hexdigest()
    assert digest(data, "sha256") == hashlib.sha256(data).hexdigest()


def test_file_digest_refuses_an_unknown_algorithm(tmp_path):
    (tmp_path / "f.bin").write_bytes(b"x")
    with pytest.raises(ValueError, match=r"^checksum: expected one of blake3, sha256, got 'md5'$"):
        file_digest(tmp_path / "f.bin", "md5")
