"""The one place that chooses the OpenGL backend and imports pyrender / PyOpenGL.

PyOpenGL fixes its platform (EGL, OSMesa, GLX) when ``OpenGL`` is first imported, from
the ``PYOPENGL_PLATFORM`` environment variable. This module sets that variable and only
then imports ``pyrender`` and ``OpenGL.GL``; nothing else in the package imports them
directly. One off-screen context is created per process and reused by every renderer:
on EGL, deleting one pyrender context tears down the display the others share.

Backends: ``"egl"`` (default, Mesa llvmpipe without a display) and ``"osmesa"`` (pure
software fallback). When the configured backend's libraries are missing (or EGL loads but
offers no device: ``libegl1`` without ``libegl-mesa0``) the other is
tried; when neither works, :class:`BackendError` names the missing library and the
``apt-get`` line that installs it.

Mesa's llvmpipe uses as many threads as cores unless ``LP_NUM_THREADS`` is set in the
environment; that is the caller's choice and is never forced here.

>>> check_backend("egl")
'egl'
"""

from __future__ import annotations

import contextlib
import ctypes
import ctypes.util
import os
import signal
import sys
import threading
from types import ModuleType

from scene.checks import check_choice

BACKENDS = ("egl", "osmesa")

#: The Debian/Ubuntu packages each backend needs.
APT_LINES = {
    "egl": "apt-get install -y libegl1 libegl-mesa0 libgl1 libgl1-mesa-dri libxrender1",
    "osmesa": "apt-get install -y libosmesa6",
}

#: Shared libraries each backend loads (sonames tried in order).
LIBRARIES = {
    "egl": (("libEGL.so.1", "libEGL.so", "EGL"), ("libGL.so.1", "libGL.so", "GL")),
    "osmesa": (("libOSMesa.so.8", "libOSMesa.so.6", "libOSMesa.so", "OSMesa"),),
}


class BackendError(RuntimeError):
    """No usable OpenGL backend; the message says what to install."""


def check_backend(backend: str) -> str:
    """Return ``backend`` if it is a known backend, else raise listing them."""
    return check_choice("render.backend", backend, BACKENDS)


def _load_library(names: tuple[str, ...]) -> str | None:
    """Load the first loadable soname of ``names``; None when none loads."""
    for name in names:
        path = name if name.startswith("lib") else ctypes.util.find_library(name)
        if not path:
            continue
        try:
            ctypes.CDLL(path)
            return path
        except OSError:
            continue
    return None


def _egl_device_count(path: str) -> int:
    """How many EGL devices libEGL at ``path`` offers (0 when it has no vendor library, e.g.
    libegl1 without libegl-mesa0): pyrender's EGL platform needs one, and PyOpenGL's platform
    cannot be switched to OSMesa once pyrender's EGL module has been imported."""
    egl = ctypes.CDLL(path)
    egl.eglGetProcAddress.restype = ctypes.c_void_p
    egl.eglGetProcAddress.argtypes = [ctypes.c_char_p]
    addr = egl.eglGetProcAddress(b"eglQueryDevicesEXT")
    if not addr:
        return 0
    query = ctypes.CFUNCTYPE(ctypes.c_uint, ctypes.c_int, ctypes.c_void_p, ctypes.POINTER(ctypes.c_int))(addr)
    count = ctypes.c_int(0)
    if not query(0, None, ctypes.byref(count)):
        return 0
    return count.value


def probe(backend: str) -> str | None:
    """None when ``backend``'s libraries load, else the name of the missing library."""
    paths = []
    for names in LIBRARIES[backend]:
        paths.append(_load_library(names))
        if paths[-1] is None:
            return names[0]
    if backend == "egl" and _egl_device_count(paths[0]) == 0:
        return "libEGL.so.1 with an EGL device (it loads, but no vendor library offers one: libegl-mesa0 missing?)"
    return None


def _imported_platform() -> str | None:
    """The platform PyOpenGL was already imported with, or None if not yet imported."""
    if "OpenGL" not in sys.modules:
        return None
    return os.environ.get("PYOPENGL_PLATFORM", "glx").lower()


def _failure(tried: list[tuple[str, str]]) -> BackendError:
    lines = ["no usable OpenGL backend for off-screen rendering:"]
    for backend, why in tried:
        lines.append(f"  {backend}: {why}; install it with: {APT_LINES[backend]}")
    return BackendError("\n".join(lines))


_CONTEXT = None  # (backend, platform) of this process; created once, never deleted


def select_backend(preferred: str = "egl") -> str:
    """The backend to use: ``preferred`` if its libraries load, else the other one.

    Raises :class:`BackendError` naming the missing libraries and the apt-get lines.
    """
    preferred = check_backend(preferred)
    if _CONTEXT is not None:
        return _CONTEXT[0]
    order = [preferred] + [b for b in BACKENDS if b != preferred]
    already = _imported_platform()
    tried = []
    for backend in order:
        if already is not None and already != backend:
            tried.append((backend, f"PyOpenGL was already imported with PYOPENGL_PLATFORM={already}"))
            continue
        missing = probe(backend)
        if missing is None:
            return backend
        tried.append((backend, f"cannot load {missing}"))
    raise _failure(tried)


def context(preferred: str = "egl"):
    """Make this process's off-screen OpenGL context current and return ``(backend, GL)``.

    The context is created on first use (a 1x1 default surface; renderers draw into
    their own framebuffer objects) and reused for the life of the process.
    """
    global _CONTEXT
    if _CONTEXT is None:
        backend = select_backend(preferred)
        os.environ["PYOPENGL_PLATFORM"] = backend
        try:
            with signals_held():
                if backend == "egl":
                    from pyrender.platforms import egl
                else:
                    from pyrender.platforms import osmesa
            if backend == "egl":
                platform = egl.EGLPlatform(1, 1, device=egl.get_default_device())
            else:
                platform = osmesa.OSMesaPlatform(1, 1)
            platform.init_context()
        except Exception as exc:  # the library loaded but no context could be made
            raise _failure([(backend, f"context creation failed ({type(exc).__name__}: {exc})")]) from exc
        _CONTEXT = (backend, platform)
    backend, platform = _CONTEXT
    platform.make_current()
    return backend, GL()


def GL() -> ModuleType:
    """The ``OpenGL.GL`` module (import only after :func:`context`)."""
    import OpenGL.GL

    return OpenGL.GL


def pyrender() -> ModuleType:
    """The ``pyrender`` module, imported with the process's backend selected."""
    if _CONTEXT is None and _imported_platform() is None:
        os.environ["PYOPENGL_PLATFORM"] = select_backend("egl")
    with signals_held():
        import pyrender as _pyrender

    return _pyrender


@contextlib.contextmanager
def signals_held():
    """Hold Ctrl-C and SIGTERM while pyrender is imported, then deliver the first that came.

    trimesh, which pyrender imports, imports its optional parts inside ``except
    BaseException``: a KeyboardInterrupt raised there was swallowed, and the run went on
    to exit 0. Only the main thread receives signals; elsewhere this does nothing.
    """
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    came: list[int] = []
    held = {s: signal.signal(s, lambda signum, frame: came.append(signum)) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, handler in held.items():
            signal.signal(s, signal.SIG_DFL if handler is None else handler)
        if came:
            signal.raise_signal(came[0])
