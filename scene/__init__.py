"""What exists: the room, calibrated cameras, people and how they move (plain data)."""

from .camera import Camera, FloorCamera, intrinsics_from_fov, rotation_from_yaw_pitch
from .config import BUILTIN_SCENES, People, RenderSettings, Scene, load_scene, scene_path
from .room import FOOT, Room

__all__ = [
    "BUILTIN_SCENES", "FOOT", "Camera", "FloorCamera", "People", "RenderSettings", "Room", "Scene",
    "intrinsics_from_fov", "load_scene", "rotation_from_yaw_pitch", "scene_path",
]
