"""What the cameras see: off-screen RGB frames, lens distortion, sensor noise, exact labels.

Nothing here imports OpenGL until a :class:`Renderer` is built (see :mod:`render.gl`).
"""

from .gl import BackendError
from .pose import opencv_to_opengl_pose, projection_matrix, view_matrix
from .renderer import Frames, Renderer

__all__ = ["BackendError", "Frames", "Renderer", "opencv_to_opengl_pose", "projection_matrix", "view_matrix"]
