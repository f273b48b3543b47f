"""Reading what the pipeline consumes: calibration files, render directories, video.

Render directory layout (written by ``camtask render``)::

    DIR/calibration/camNN.yaml   cv2.FileStorage: camera_matrix, distortion_coefficients,
                                 rvec, tvec (world -> camera, metres), image_width, image_height
    DIR/frames/camNN/NNNNNN.png  RGB frames (stored by OpenCV as BGR on disk)
    DIR/frames/camNN.mkv         or the same frames as one lossless video per camera (``--format video``)
    DIR/masks/camNN/NNNNNN.png   labels: 0 background, person id + 1 elsewhere
    DIR/background/camNN.png     the empty room
"""

from __future__ import annotations

import io
import os
import re
from pathlib import Path

import cv2
import numpy as np

from scene.camera import Camera
from scene.checks import check_input_file, names

from .files import write_atomic

IMAGE_SUFFIXES = (".png", ".jpg", ".jpeg", ".bmp", ".tif", ".tiff", ".ppm", ".pgm")
#: OpenCV's distortion terms after k1 k2 p1 p2 k3 (rational, thin prism, tilted sensor): a
#: calibration may hold them when zero
EXTRA_TERMS = ("k4", "k5", "k6", "s1", "s2", "s3", "s4", "tauX", "tauY")


def load_calibration(path: str | os.PathLike, number: int | None = None, name: str = "calibration") -> Camera:
    """A :class:`Camera` from an OpenCV calibration file (YAML/XML, FileStorage).

    number : camera number; by default the file's ``camera_number`` (``camtask render``
    writes it), else ``camNN`` in the file name, else 1.
    name : what the messages call the file (the option that gave it: ``--calibration``).
    Every problem is a one-line ValueError naming the file and the key.
    """
    path = check_input_file(name, path)
    try:
        fs = cv2.FileStorage(str(path), cv2.FILE_STORAGE_READ)
        opened = fs.isOpened()
    except (cv2.error, SystemError):
        opened = False
    if not opened:
        raise ValueError(f"{name}: {path.name} is not an OpenCV FileStorage file (YAML or XML "
                         "with camera_matrix, distortion_coefficients, rvec, tvec, image_width, image_height)")
    try:
        def node(key, required=True):
            n = fs.getNode(key)
            if n.empty() and required:
                raise ValueError(f"{name}: {path.name} has no {key!r}")
            return None if n.empty() else n

        def matrix(key, size):
            n = node(key)
            if n.isSeq():                                  # a list of numbers, e.g. [a, b, c]
                m = [n.at(i).real() if n.at(i).isReal() or n.at(i).isInt() else np.nan for i in range(n.size())]
            else:
                m = n.real() if n.isReal() or n.isInt() else n.mat()
            m = None if m is None else np.asarray(m, float).ravel()
            if m is None or (size is not None and m.size != size) or not np.all(np.isfinite(m)):
                raise ValueError(f"{name}: {path.name} {key}: expected {size or 'up to 5'} finite numbers")
            return m

        def integer(key, required=True):
            n = node(key, required)
            if n is None:
                return None
            if not n.isInt():
                raise ValueError(f"{name}: {path.name} {key}: expected an integer")
            return int(n.real())

        K = matrix("camera_matrix", 9).reshape(3, 3)
        dist = matrix("distortion_coefficients", None)
        rvec, tvec = matrix("rvec", 3), matrix("tvec", 3)
        width, height = integer("image_width"), integer("image_height")
        stored_number = integer("camera_number", required=False)
    finally:
        fs.release()
    if dist.size < 5:
        dist = np.concatenate([dist, np.zeros(5 - dist.size)])
    elif dist.size > 5:
        if np.any(dist[5:] != 0):
            i = 5 + int(np.flatnonzero(dist[5:])[0])
            term = EXTRA_TERMS[i - 5] if i - 5 < len(EXTRA_TERMS) else f"coefficient {i + 1}"
            raise ValueError(f"{name}: {path.name} distortion_coefficients: expected at most 5 "
                             f"(k1 k2 p1 p2 k3), got {dist.size} with {term} = {dist[i]:g} "
                             "(the terms past k3 must be zero)")
        dist = dist[:5]
    if number is None:
        number = stored_number if stored_number is not None else number_in_name(path, default=1)
    R, _ = cv2.Rodrigues(rvec)
    try:
        return Camera(number, K, dist, R, tvec, width, height)
    except ValueError as exc:
        raise ValueError(f"{name}: {path.name}: {exc}") from None


def check_camera(camera: Camera, name: str) -> None:
    """Raise a one-line ValueError starting with ``name`` (the option, or the file, that gave
    ``camera``) unless its lens maps rays one to one onto its image and it can be rectified
    to a level camera (:func:`pipeline.rectify.check_rectifiable`): a lens that folds over
    would be remapped into scanlines and bearings of rays it renders twice."""
    from .rectify import check_rectifiable

    check_rectifiable([camera], [name])


def number_in_name(path: str | os.PathLike, default: int | None = None) -> int | None:
    """The camera number ``NN`` of a ``camNN`` file name, else ``default``."""
    m = re.search(r"cam(\d+)", Path(path).stem)
    return int(m.group(1)) if m else default


def read_rgb(path: str | os.PathLike, name: str = "image") -> np.ndarray:
    """(H, W, 3) uint8 RGB image from a file (OpenCV reads BGR; converted here).

    name : what the error message starts with (the file's role, or the option naming it)
    """
    img = cv2.imread(str(path), cv2.IMREAD_COLOR)
    if img is None:
        raise ValueError(f"{name}: cannot read {str(path)!r}")
    return cv2.cvtColor(img, cv2.COLOR_BGR2RGB)


def read_labels(path: str | os.PathLike) -> np.ndarray:
    """(H, W) int label image (0 background) from a PNG (8 or 16 bit, one channel): a
    label mask (``masks/``) or a person's silhouettes (``silhouettes/``)."""
    img = cv2.imread(str(path), cv2.IMREAD_UNCHANGED)
    if img is None:
        raise ValueError(f"label image: cannot read {str(path)!r}")
    if img.ndim == 3:
        img = img[..., 0]
    return img.astype(np.int32)


class RenderDir:
    """A render directory: cameras, background, and frames/labels by frame index.

    cameras : tuple of :class:`Camera`, in camera-number order
    frame_names : sorted frame file names (``NNNNNN.png``) common to all cameras
    name : what its error messages start with (``DIR``)
    """

    def __init__(self, root: str | os.PathLike, name: str = "DIR"):
        """name : what error messages start with: the argument or option that gave ``root``."""
        self.root = Path(root)
        self.name = name
        if not self.root.is_dir():
            if self.root.exists():
                raise ValueError(f"{name}: {str(self.root)!r} is a file, not a folder (a render directory "
                                 "written by `camtask render`)")
            raise FileNotFoundError(f"{name}: no such folder {str(self.root)!r}")
        # in number order (cam100 after cam99, not between cam10 and cam11 as text sorts it)
        calib = sorted((self.root / "calibration").glob("cam*.yaml"), key=lambda p: number_order(p.name))
        if not calib:
            raise ValueError(f"{name}: {self.root} is not a render directory: it has no calibration/camNN.yaml files")
        # numbered as the files (and so the frames/camNN folders) are named
        self.cameras = tuple(load_calibration(p, number_in_name(p)) for p in calib)
        for cam, path in zip(self.cameras, calib):
            if path.stem != cam.name:           # camera N's frames, masks, ... are looked for as camNN
                want = f"{cam.name}{path.suffix} for camera {cam.number}" if number_in_name(path) else "camNN.yaml"
                raise ValueError(f"{name}: {path.relative_to(self.root)}: expected the name {want} (camNN, the "
                                 "camera's number in two digits or more, as `camtask render` writes)")
        from .rectify import check_rectifiable

        # as `camtask render` checks its scene's: each lens once, not once per camera
        check_rectifiable(self.cameras, [f"{name}: {p.relative_to(self.root)}" for p in calib])
        for cam, path in zip(self.cameras, calib):
            if (cam.width, cam.height) != (self.cameras[0].width, self.cameras[0].height):
                raise ValueError(f"{name}: {path.relative_to(self.root)} is {cam.width}x{cam.height} pixels, "
                                 f"{calib[0].relative_to(self.root)} {self.cameras[0].width}x{self.cameras[0].height}; "
                                 "the node pipeline takes cameras of one resolution")
        self.names = tuple(c.name for c in self.cameras)
        uncalibrated = sorted(p for p in (self.root / "frames").glob("cam*")
                              if p.stem not in self.names and (p.is_dir() or p.suffix == ".mkv"))
        if uncalibrated:                        # its frames would be left out without a word
            odd = uncalibrated[0]
            raise ValueError(f"{name}: {odd.relative_to(self.root)} has no calibration/{odd.stem}.yaml; every "
                             "camera's frames need its calibration")
        first = self.root / "frames" / self.names[0]
        self.frame_names = tuple(sorted(p.name for p in first.glob("*.png")))
        #: frames/camNN.mkv of each camera (`camtask render --format video`), else None: PNG frames
        self.videos = None
        kind = "frames"
        if not self.frame_names and first.with_name(f"{self.names[0]}.mkv").is_file():
            self.videos = tuple(self.root / "frames" / f"{n}.mkv" for n in self.names)
            kind, first = "masks", self.root / "masks" / self.names[0]      # the frames' names are the masks'
            self.frame_names = tuple(sorted(p.name for p in first.glob("*.png")))
        self._decoders, self._next = None, 0    # the videos' readers, and the frame they yield next
        self._last = None                       # (index, frames) last decoded: read again without decoding
        if not self.frame_names:
            raise ValueError(f"{name}: {first} has no frames")
        for cam in self.names[1:]:              # frame i is the same moment in every camera
            other = self.root / kind / cam
            names = tuple(sorted(p.name for p in other.glob("*.png")))
            if names != self.frame_names:
                odd = sorted(set(names) ^ set(self.frame_names))
                raise ValueError(f"{name}: {other} and {first} hold different frames ({len(names)} and "
                                 f"{len(self.frame_names)}; {odd[0]} is in one only); frames are matched by name")

    def __len__(self) -> int:
        return len(self.frame_names)

    def check_complete(self, frames: int) -> None:
        """Refuse, in one line before any frame is read, a render directory that lacks a
        frame, label image or background of its first ``frames`` frames (one missing at frame
        250 was found after reading the 249 before it)."""
        kinds = ("masks",) if self.videos else ("frames", "masks")
        wanted = [Path("background") / f"{c}.png" for c in self.names] + [
            Path(kind) / c / f for f in self.frame_names[:frames] for kind in kinds for c in self.names]
        wanted += [p.relative_to(self.root) for p in self.videos or ()]
        missing = [str(p) for p in wanted if not (self.root / p).is_file()]
        if missing:
            raise ValueError(f"{self.name}: {self.root} lacks {len(missing)} file{'' if len(missing) == 1 else 's'} "
                             f"of its first {frames} frame{'' if frames == 1 else 's'}: {names(missing)}")

    def _stack(self, what: str, paths, reader) -> np.ndarray:
        images = []
        for cam, path in zip(self.cameras, paths):
            img = reader(path)
            if img.shape[:2] != (cam.height, cam.width):
                raise ValueError(f"{what}: {path.relative_to(self.root)} is {img.shape[1]}x{img.shape[0]}; "
                                 f"expected {cam.width}x{cam.height} to match the calibration")
            images.append(img)
        return np.stack(images)

    def background(self) -> np.ndarray:
        """(n_cams, H, W, 3) uint8 RGB empty-room images."""
        return self._stack("background", [self.root / "background" / f"{n}.png" for n in self.names], read_rgb)

    def frames(self, index: int) -> np.ndarray:
        """(n_cams, H, W, 3) uint8 RGB frame ``index`` (0-based) of every camera.

        From videos, frames are decoded in order by one ffmpeg per camera, kept between calls
        (:func:`testbed.lossless.read_video`: a truncated or corrupt video, or one of another
        number of frames than the masks, is a one-line ValueError naming it, after which the
        next call starts the videos again): reading them in order costs one decoding, the
        last frame again none; an earlier index than the last starts the videos again.
        """
        if self.videos is None:
            f = self.frame_names[index]
            return self._stack("frames", [self.root / "frames" / n / f for n in self.names], read_rgb)
        index = range(len(self))[index]         # as a list indexes: negative from the end, IndexError past it
        if self._last is not None and self._last[0] == index:
            return self._last[1].copy()
        if self._decoders is None or index < self._next:
            from testbed.lossless import read_video

            self.close()
            self._decoders, self._next = [read_video(p, len(self)) for p in self.videos], 0
        try:
            while True:
                images = dict(zip(self.videos, [next(d) for d in self._decoders]))
                self._next += 1
                if self._next == len(self):     # read to their end: a longer video is not of these masks
                    for path, decoder in zip(self.videos, self._decoders):
                        if next(decoder, None) is not None:
                            raise ValueError(f"video: {str(path)!r} holds more than {len(self)} frames; "
                                             f"expected {len(self)}, as masks/{path.stem} has")
                if self._next > index:
                    stack = self._stack("frames", self.videos, images.__getitem__)
                    self._last = (index, stack)
                    return stack.copy()
        except BaseException:                   # the decoders stand at different frames now: start again
            self.close()
            raise

    def close(self) -> None:
        """Stop the ffmpeg processes decoding the videos (they also stop when this is collected)."""
        for decoder in self._decoders or ():
            decoder.close()
        self._decoders, self._last = None, None

    def labels(self, index: int) -> np.ndarray:
        """(n_cams, H, W) int label images of frame ``index``."""
        f = self.frame_names[index]
        return self._stack("masks", [self.root / "masks" / n / f for n in self.names], read_labels)


def number_order(name: str) -> tuple:
    """A sort key that orders the numbers in names by value: ``frame2`` before ``frame10``
    (as text, ``frame10`` came first), zero-padded names as text does; equal keys (``f01``,
    ``f1``) by the name itself."""
    parts = re.split(r"(\d+)", name)                     # text, number, text, ...: aligned
    return tuple(int(t) if k % 2 else t for k, t in enumerate(parts)), name


def image_files(folder: Path) -> list[Path]:
    """The images of ``folder`` in the order :func:`iter_video_frames` reads them: by the
    numbers in their names (:func:`number_order`)."""
    return sorted((p for p in folder.iterdir() if p.suffix.lower() in IMAGE_SUFFIXES),
                  key=lambda p: number_order(p.name))


def iter_video_frames(source: str | os.PathLike, name: str = "--video"):
    """Yield (H, W, 3) uint8 RGB frames of a video file or of a folder of images (in the
    order of the numbers in their names, :func:`number_order`). A video is decoded by
    :func:`testbed.lossless.read_video`: a truncated or corrupt one is a one-line ValueError
    naming it, raised before a damaged frame would be yielded.

    name : what error messages start with: the option that gave ``source``.
    """
    source = Path(source)
    if source.is_dir():
        files = image_files(source)
        if not files:
            raise ValueError(f"{name}: folder {str(source)!r} has no images ({', '.join(IMAGE_SUFFIXES)})")
        for p in files:
            yield read_rgb(p, name)
        return
    if not source.is_file():
        if source.exists():
            raise ValueError(f"{name}: {str(source)!r} is neither a video file nor a folder of images")
        raise FileNotFoundError(f"{name}: no such file or folder {str(source)!r}")
    from testbed.lossless import read_video

    # ffmpeg with its errors checked (cv2.VideoCapture decoded a slice whose CRC failed as
    # ffmpeg concealed it, and ended a truncated video early without a word): the same pixels
    yield from read_video(source, name=name)


def save_npz_atomic(path: str | os.PathLike, **arrays) -> None:
    """``np.savez_compressed`` of ``arrays`` written by :func:`pipeline.files.write_atomic`:
    a temporary file beside ``path`` (its folder made when missing), then os.replace; a
    symbolic link written through; an error writing names the file."""
    buffer = io.BytesIO()
    np.savez_compressed(buffer, **arrays)
    write_atomic(path, buffer.getbuffer())
