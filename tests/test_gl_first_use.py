"""First use without working OpenGL: a clear error, no traceback; EGL without a device falls back."""

import os
import subprocess
import sys

import pytest

from testbed.cli import main

ROOT = os.path.dirname(os.path.dirname(os.path.abspath(__file__)))


def test_no_gl_backend_is_an_error_message_not_a_traceback(monkeypatch, capsys, tmp_path):
    from render import gl

    monkeypatch.setattr(gl, "_CONTEXT", None)
    monkeypatch.setattr(gl, "_imported_platform", lambda: None)
    monkeypatch.setattr(gl, "probe", lambda backend: {"egl": "libEGL.so.1", "osmesa": "libOSMesa.so.8"}[backend])
    rc = main(["render", "lab", "--frames", "1", "--cameras", "1", "--out", str(tmp_path / "out")])
    err = capsys.readouterr().err
    assert rc == 1
    assert "camtask render: error: no usable OpenGL backend" in err
    assert "apt-get install -y libosmesa6" in err


def test_egl_library_without_a_device_falls_back_to_osmesa():
    """libegl1 (glvnd) loads but no vendor offers a device, as without libegl-mesa0."""
    code = "from render import gl; print(gl.probe('osmesa')); print(gl.select_backend('egl'))"
    env = dict(os.environ, __EGL_VENDOR_LIBRARY_DIRS="/nonexistent", PYTHONPATH=ROOT)
    out = subprocess.run([sys.executable, "-c", code], env=env, capture_output=True, text=True, check=True).stdout.split()
    if out[0] != "None":
        pytest.skip("OSMesa is not installed")
    assert out[1] == "osmesa"
