"""Scenes from YAML: the room, its cameras, the people and the render settings.

A scene file is parsed once with PyYAML's safe loader (its libyaml binding when present:
5 -> 0.7 ms for the 16-camera lab; ``1e-3`` read as a number, :mod:`scene.yamlio`) into a
frozen, validated :class:`Scene`. Every error is one line naming the field and what was
expected.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from pathlib import Path
from typing import Any

import numpy as np
import yaml

from . import yamlio
from .camera import FLOOR_FOV_RANGE, Camera, FloorCamera
from .checks import (
    check_array,
    check_between,
    check_choice,
    check_finite,
    check_int,
    check_mapping,
    read_input_text,
    readonly,
    shown,
)
from .room import Room

ASSETS = Path(__file__).resolve().parent.parent / "assets"
#: The widest or tallest image, pixels: OpenGL renders into buffers of at most 16384 a
#: side on llvmpipe, and each camera's canvas adds at least 2 pixels on each side (lens
#: distortion can ask for more: such a camera is refused when its renderer is built).
MAX_RESOLUTION = 16380
#: Frame rates, Hz: below one frame in about 17 minutes a walk is a teleport (and at 1e-300 Hz the
#: tracker's dt**2 overflowed); 1e300 Hz failed in ffmpeg after `run --video` had started (10**4
#: writes; `render --format video` takes at most 1000, testbed.lossless.MAX_FPS).
FRAME_RATE_RANGE = (1e-3, 1e4)
#: The largest room side (a rectangle's width, depth, a circle's radius, any room's height), metres:
#: the rendered floor is 1-ft tiles, 11 s and 0.65 GB for a 100 m room, 50 s and 1.7 GB for 300 m,
#: memory without end for 10**6 m (and 1e300 m overflowed); at 100 m the lab's cameras see a person
#: a few pixels wide.
MAX_ROOM_SIZE = 100.0
#: The smallest person (radius and height), metres: a 1e-300 m radius underflowed the capacity check.
MIN_PERSON_SIZE = 1e-3
#: The fastest walk, m/s: at 1e300 m/s the tracker's process noise overflowed.
MAX_SPEED = 100.0
#: The most cameras in a ring (as the studies' ``--cameras``): a ring of 10**9 filled the memory
#: building them one by one.
MAX_RING_CAMERAS = 10_000
#: The narrowest and widest horizontal field of view of a calibrated camera, degrees. OpenGL
#: draws in float32, whose error grows with the focal length: a 640-pixel camera drew a
#: person's edge 1.3 px off at 0.001 degrees (focal length 3.7e7 pixels; at 1e-10 degrees it
#: saw nothing; at 1e-300 the rectification blamed the principal point); at 1 degree the
#: widest image (MAX_RESOLUTION) has a focal length of 9.4e5 pixels, 40 times less. At 179
#: degrees the image's edges look 89.5 degrees off its axis.
HFOV_RANGE = (1.0, 179.0)
BUILTIN_SCENES = ("lab", "circle")
BACKENDS = ("egl", "osmesa")


@dataclass(frozen=True, eq=False)
class People:
    """Who walks in the scene.

    count : number of people
    radius, height : metres (upright cylinders)
    speed : metres per second (random-waypoint walking speed)
    colours : (count, 3) uint8 clothing colours, RGB
    positions : (count, 2) float metres, world frame, or None to drop them at random
    """

    count: int
    radius: float
    height: float
    speed: float
    colours: np.ndarray
    positions: np.ndarray | None = None


@dataclass(frozen=True)
class RenderSettings:
    """How frames are rendered and degraded (plain data; used by ``render/``).

    backend : "egl" (default) or "osmesa" (fallback when EGL is unavailable)
    noise_std : std of additive Gaussian sensor noise, 8-bit grey levels
    gain_jitter : std of the per-frame, per-camera multiplicative illumination change
    """

    backend: str = "egl"
    noise_std: float = 2.0
    gain_jitter: float = 0.02


@dataclass(frozen=True, eq=False)
class Scene:
    """A room, its cameras, the people in it, and how it is rendered.

    cameras : tuple of :class:`Camera` (calibrated, the lab) or :class:`FloorCamera` (circle),
        in number order whatever the file's order: ``cameras[i].number == i + 1``
    frame_rate : frames per second of the simulated network
    uniform_sets : the paper's hand-picked uniform taskings, k -> camera numbers
    """

    name: str
    room: Room
    cameras: tuple
    people: People
    frame_rate: float = 7.5
    render: RenderSettings = field(default_factory=RenderSettings)
    uniform_sets: Mapping[int, tuple[int, ...]] = field(default_factory=dict)

    @property
    def dt(self) -> float:
        """Time between frames, seconds."""
        return 1.0 / self.frame_rate

    @property
    def is_calibrated(self) -> bool:
        """True when every camera is a calibrated pinhole camera (renderable)."""
        return all(isinstance(c, Camera) for c in self.cameras)

    def floor_poses(self) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """Floor-plane poses for tasking: xy (n, 2) metres, yaw (n,) radians, fov (n,) radians."""
        xy = np.array([c.xy for c in self.cameras], dtype=float)
        yaw = np.array([c.yaw for c in self.cameras], dtype=float)
        fov = np.array([c.fov for c in self.cameras], dtype=float)
        return xy, yaw, fov

    def uniform_indices(self) -> dict[int, tuple[int, ...]]:
        """The uniform sets as 0-based camera indices, k -> indices."""
        return {k: tuple(n - 1 for n in nums) for k, nums in self.uniform_sets.items()}

    @staticmethod
    def from_config(config: Any, *, source: str = "scene") -> Scene:
        """Build and validate a scene from a parsed YAML document."""
        return _parse_scene(config, source)

    @staticmethod
    def from_yaml(path: str | Path) -> Scene:
        """Load a scene file."""
        return Scene.from_text(read_scene_text(path), str(path))

    @staticmethod
    def from_text(text: str, source: str = "scene") -> Scene:
        """Build and validate a scene from the text of a scene file (``source`` names it in errors)."""
        try:
            config = yamlio.load(text)
        except yaml.YAMLError as exc:
            raise ValueError(f"{source}: not valid YAML ({yamlio.error_text(exc, text)})") from None
        return _parse_scene(config, source)


def load_scene(name_or_path: str | Path) -> Scene:
    """A built-in scene by name (``lab``, ``circle``) or a scene file by path.

    >>> load_scene("lab").room.area > 38
    True
    """
    return Scene.from_yaml(scene_file(name_or_path))


def scene_file(name_or_path: str | Path) -> Path:
    """The file of a built-in scene by name (``lab``, ``circle``), else the path itself."""
    return scene_path(str(name_or_path)) if str(name_or_path) in BUILTIN_SCENES else Path(name_or_path)


def read_scene_text(path: str | Path) -> str:
    """The text of a scene file; a one-line error when it is missing or not a file (:func:`scene.checks.read_input_text`)."""
    return read_input_text("scene file", path)


def scene_path(name: str) -> Path:
    """Path of a built-in scene file."""
    check_choice("scene", name, BUILTIN_SCENES)
    return ASSETS / "scenes" / f"{name}.yaml"


def _parse_scene(config: Any, source: str) -> Scene:
    if config is None:
        raise ValueError(f"{source}: empty scene file; expected a mapping with room, cameras, people")
    if not isinstance(config, Mapping):
        raise ValueError(f"{source}: expected a mapping at the top level, got {type(config).__name__}")
    check_mapping("scene", config, ("name", "frame_rate", "room", "cameras", "people", "render", "uniform_sets"),
                  ("room", "cameras", "people"))
    room = _parse_room(config["room"])
    cameras = _parse_cameras(config["cameras"], room)
    people = _parse_people(config["people"], room)
    render = _parse_render(config.get("render", {}) or {})
    uniform = _parse_uniform_sets(config.get("uniform_sets", {}) or {}, len(cameras))
    name = config.get("name", Path(source).stem)
    if not isinstance(name, str) or not name:
        raise ValueError(f"name: expected a non-empty string, got {name!r}")
    return Scene(
        name=name,
        room=room,
        cameras=cameras,
        people=people,
        frame_rate=check_between("frame_rate", config.get("frame_rate", 7.5), *FRAME_RATE_RANGE, "Hz"),
        render=render,
        uniform_sets=uniform,
    )


def _parse_room(cfg: Any) -> Room:
    check_mapping("room", cfg, ("shape", "width", "depth", "radius", "height"), ("shape",))
    shape = check_choice("room.shape", cfg["shape"], ("rectangle", "circle"))
    for key in ("width", "depth", "radius", "height"):
        if key in cfg:
            check_between(f"room.{key}", cfg[key], 0.0, MAX_ROOM_SIZE, "m", low_open=True)
    if shape == "rectangle":
        check_mapping("room", cfg, ("shape", "width", "depth", "height"), ("width", "depth", "height"))
        return Room.rectangle(cfg["width"], cfg["depth"], cfg["height"])
    check_mapping("room", cfg, ("shape", "radius", "height"), ("radius",))
    return Room.circle(cfg["radius"], cfg.get("height", 2.5))


def _parse_cameras(cfg: Any, room: Room) -> tuple:
    check_mapping("cameras", cfg, ("intrinsics", "poses", "ring"))
    if "ring" in cfg:
        if len(cfg) > 1:
            raise ValueError("cameras: expected either ring or intrinsics and poses, not both")
        return _parse_ring(cfg["ring"], room)
    check_mapping("cameras", cfg, ("intrinsics", "poses"), ("intrinsics", "poses"))
    intr = check_mapping("cameras.intrinsics", cfg["intrinsics"],
                         ("resolution", "hfov_deg", "principal", "distortion"),
                         ("resolution", "hfov_deg", "distortion"))
    res = intr["resolution"]
    if not (isinstance(res, (list, tuple)) and len(res) == 2):
        raise ValueError(f"cameras.intrinsics.resolution: expected [width, height], got {res!r}")
    width = check_int("cameras.intrinsics.resolution", res[0], minimum=2)    # a scanline needs 2 columns
    height = check_int("cameras.intrinsics.resolution", res[1], minimum=2)
    if max(width, height) > MAX_RESOLUTION:
        raise ValueError(f"cameras.intrinsics.resolution: expected at most {MAX_RESOLUTION} pixels a side, "
                         f"got {shown(width)} x {shown(height)}")
    hfov = _check_fov("cameras.intrinsics.hfov_deg", intr["hfov_deg"], *HFOV_RANGE)
    dist = check_array("cameras.intrinsics.distortion", intr["distortion"], (5,))
    principal = intr.get("principal")
    if principal is not None:
        principal = check_principal("cameras.intrinsics.principal", principal, width, height)
    poses = cfg["poses"]
    if not isinstance(poses, list) or not poses:
        raise ValueError("cameras.poses: expected a non-empty list of camera poses")
    cameras = []
    for i, pose in enumerate(poses):
        where = f"cameras.poses[{i}]"
        check_mapping(where, pose, ("number", "position", "yaw_deg", "pitch_deg"),
                      ("number", "position", "yaw_deg", "pitch_deg"))
        number = check_int(f"{where}.number", pose["number"], minimum=1)
        pos = check_array(f"{where}.position", pose["position"], (3,))
        if not room.contains_point(pos[:2]) or not 0 < pos[2] < room.height:
            raise ValueError(f"{where}.position: camera {shown(number)} at {pos.tolist()} is outside the room")
        yaw = check_between(f"{where}.yaw_deg", pose["yaw_deg"], -360.0, 360.0, "degrees")
        pitch = check_finite(f"{where}.pitch_deg", pose["pitch_deg"])
        if not -90 < pitch < 90:
            raise ValueError(f"{where}.pitch_deg: expected a pitch in (-90, 90) degrees (down is positive), "
                             f"got {pose['pitch_deg']!r}")
        cameras.append(Camera.from_pose(
            number, pos,
            np.radians(yaw), np.radians(pitch), width, height, hfov, dist, principal))
    _check_numbers(cameras)
    return tuple(sorted(cameras, key=lambda c: c.number))     # cameras[i] is camera number i + 1


def _parse_ring(cfg: Any, room: Room) -> tuple:
    check_mapping("cameras.ring", cfg, ("count", "fov_deg"), ("count", "fov_deg"))
    if room.kind != "circle":
        raise ValueError("cameras.ring: a ring of cameras needs a circular room")
    n = check_int("cameras.ring.count", cfg["count"], minimum=1)
    if n > MAX_RING_CAMERAS:
        raise ValueError(f"cameras.ring.count: expected at most {MAX_RING_CAMERAS} cameras, got {shown(n)}")
    fov = _check_fov("cameras.ring.fov_deg", cfg["fov_deg"], *FLOOR_FOV_RANGE)
    radius = float(np.max(np.linalg.norm(room.vertices, axis=1)))
    angles = 2 * np.pi * np.arange(n) / n
    return tuple(
        FloorCamera(i + 1, radius * np.array([np.cos(a), np.sin(a)]), float(np.arctan2(-np.sin(a), -np.cos(a))), fov)
        for i, a in enumerate(angles)
    )


def _check_fov(name: str, value: Any, minimum: float, maximum: float) -> float:
    """A field of view in degrees, at most ``maximum`` and at least ``minimum`` (more than 0 for
    ``minimum`` 0), as radians."""
    try:
        deg = None if isinstance(value, (bool, str, bytes)) else float(value)
    except (TypeError, ValueError, OverflowError):
        deg = None
    if deg is None or not (minimum <= deg <= maximum and deg > 0):
        low = "(0" if minimum == 0 else f"[{minimum:g}"
        raise ValueError(f"{name}: expected a field of view in {low}, {maximum:g}] degrees, got {shown(value)}")
    return float(np.radians(deg))


def check_principal(name: str, value: Any, width: int, height: int) -> np.ndarray:
    """The principal point ``value`` (2,) pixels (u, v) of a ``width`` x ``height`` image, at
    most one image width (height) outside its pixels' edges, else a one-line error: the
    optical axis of a camera whose principal point is farther off meets nothing it sees, the
    focal length that ``hfov_deg`` gives (from half the width) no longer tells its view, and at
    1e300 the lens checks failed with NaN and blamed the distortion.

    >>> check_principal("principal", [1e300, 236.8], 640, 480)
    Traceback (most recent call last):
    ...
    ValueError: principal: expected [u, v] pixels at most one image size outside the image, u in -640.5..1279.5 and v in -480.5..959.5, got [1e+300, 236.8]
    """
    uv = check_array(name, value, (2,))
    lo, hi = -0.5 - np.array([width, height]), np.array([2 * width, 2 * height]) - 0.5
    if not np.all((lo <= uv) & (uv <= hi)):
        raise ValueError(f"{name}: expected [u, v] pixels at most one image size outside the image, "
                         f"u in {lo[0]:g}..{hi[0]:g} and v in {lo[1]:g}..{hi[1]:g}, got [{uv[0]:g}, {uv[1]:g}]")
    return uv


def _check_numbers(cameras) -> None:
    numbers = sorted(c.number for c in cameras)
    if numbers != list(range(1, len(cameras) + 1)):
        raise ValueError(f"cameras.poses: expected camera numbers 1..{len(cameras)} once each, "
                         f"got [{', '.join(map(shown, numbers))}]")


def _parse_people(cfg: Any, room: Room) -> People:
    check_mapping("people", cfg, ("count", "radius", "height", "speed", "colours", "positions"), ("count", "radius"))
    count = check_int("people.count", cfg["count"], minimum=0)
    radius = check_between("people.radius", cfg["radius"], MIN_PERSON_SIZE, np.inf, "m")
    height = check_between("people.height", cfg.get("height", 1.75), MIN_PERSON_SIZE, np.inf, "m")
    if height > room.height:
        raise ValueError(f"people.height: {height:g} m is above the ceiling ({room.height:g} m, room.height)")
    speed = check_between("people.speed", cfg.get("speed", 1.0), 0.0, MAX_SPEED, "m/s", low_open=True)
    check_person_fits("people.radius", radius, room)
    positions = cfg.get("positions")        # before the colours: a count of 10**9 is refused, not allocated
    if positions is None:
        check_people_capacity("people.count", count, radius, room)
    else:
        if count == 0 and isinstance(positions, list) and not positions:
            positions = np.zeros((0, 2))
        positions = check_array("people.positions", positions, (count, 2))
        check_people_fit(positions, radius, room)
        positions = readonly(positions)
    colours = cfg.get("colours")
    if colours is None:
        colours = default_colours(count)
    colours = check_array("people.colours", colours, (None, 3))
    if len(colours) < count or np.any(colours < 0) or np.any(colours > 255) or np.any(colours != np.round(colours)):
        raise ValueError(f"people.colours: expected at least {shown(count)} RGB triples of integers in 0..255")
    return People(count, radius, height, speed, readonly(colours[:count].astype(np.uint8)), positions)


def check_people_capacity(name: str, count: int, radius: float, room: Room) -> None:
    """Raise if ``count`` people of ``radius`` metres are too many to drop at random in ``room``.

    At most a quarter of the floor may be covered: random drops and walks need room
    to move (a dense crowd is possible with given ``positions``).
    """
    capacity = room.area / (np.pi * radius**2) / 4
    if count > capacity:
        raise ValueError(f"{name}: {shown(count)} people of radius {radius:g} m do not fit in the room; "
                         f"expected at most {int(capacity)}")


def check_person_fits(name: str, radius: float, room: Room) -> None:
    """Raise if no disc of ``radius`` metres fits inside ``room`` (a corridor narrower than a person)."""
    if room.polygon.buffer(-radius).is_empty:
        raise ValueError(f"{name}: a person of radius {radius:g} m does not fit anywhere in the room")


def check_people_fit(positions: np.ndarray, radius: float, room: Room) -> None:
    """Raise if a person overlaps a wall or another person (positions (m, 2) metres)."""
    for i, p in enumerate(positions):
        if not room.contains_disc(p, radius):
            raise ValueError(f"people.positions[{i}]: person at {p.tolist()} overlaps a wall or is outside the room")
    if len(positions) > 1:
        d = np.linalg.norm(positions[:, None] - positions[None], axis=-1)
        i, j = np.triu_indices(len(positions), 1)
        bad = np.flatnonzero(d[i, j] < 2 * radius)
        if bad.size:
            raise ValueError(f"people.positions[{j[bad[0]]}]: person overlaps person {i[bad[0]]}")


def default_colours(count: int) -> np.ndarray:
    """Distinct, saturated clothing colours, (count, 3) uint8 RGB.

    Each is at least 22 degrees (colour angle) from every pixel of the lab's empty room, so
    the pipeline's brightness-blind colour-angle test sees them all (a grey one was
    invisible against the grey walls and floor, and the hull lost every tenth person).
    """
    palette = np.array([[200, 30, 30], [30, 70, 200], [30, 160, 50], [230, 170, 20], [150, 40, 170],
                        [20, 170, 180], [240, 110, 20], [110, 60, 20], [230, 60, 150], [150, 200, 30]])
    return palette[np.arange(count) % len(palette)]


def _parse_render(cfg: Any) -> RenderSettings:
    check_mapping("render", cfg, ("backend", "noise_std", "gain_jitter"))
    return RenderSettings(
        backend=check_choice("render.backend", cfg.get("backend", "egl"), BACKENDS),
        # noise beyond the 8-bit range, or a gain jitter beyond 100 %, leaves no picture to test
        noise_std=check_between("render.noise_std", cfg.get("noise_std", 2.0), 0.0, 255.0, "grey levels"),
        gain_jitter=check_between("render.gain_jitter", cfg.get("gain_jitter", 0.02), 0.0, 1.0, "(relative)"),
    )


def _parse_uniform_sets(cfg: Any, n_cameras: int) -> dict[int, tuple[int, ...]]:
    if not isinstance(cfg, Mapping):
        raise ValueError("uniform_sets: expected a mapping k -> list of camera numbers")
    out = {}
    for k, nums in cfg.items():
        k = check_int("uniform_sets key", k, minimum=1)
        where = f"uniform_sets[{shown(k)}]"
        if not isinstance(nums, list):
            raise ValueError(f"{where}: expected a list of {shown(k)} camera numbers, got {nums!r}")
        nums = tuple(check_int(where, n) for n in nums)
        if len(nums) != k or len(set(nums)) != k or not all(1 <= n <= n_cameras for n in nums):
            raise ValueError(f"{where}: expected {shown(k)} distinct camera numbers in 1..{n_cameras}")
        out[k] = tuple(sorted(nums))
    return out
