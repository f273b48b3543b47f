"""What a node sends: frames -> colour-angle foreground -> opening -> undistortion and
rectification to a level camera -> column sums -> smoothing -> median -> scanline -> RLE."""

from .core import Pipeline, StepOutput
from .foreground import background_model, colour_angle_foreground, open_masks
from .metrics import cdnet_metrics, confusion, evaluate
from .nearfield import sight_range
from .params import PipelineParams, load_params
from .rectify import Rectifier, column_bearings, level_rotation, virtual_camera_matrix
from .rle import bits_per_run, rle_bits, rle_decode, rle_encode, scanline_bits
from .scanline import median_threshold, spatial_smooth, temporal_smooth, true_scanlines

__all__ = [
    "Pipeline", "PipelineParams", "Rectifier", "StepOutput", "background_model", "bits_per_run",
    "cdnet_metrics", "colour_angle_foreground", "column_bearings", "confusion",
    "evaluate", "level_rotation", "load_params", "median_threshold", "open_masks", "rle_bits",
    "rle_decode", "rle_encode", "scanline_bits", "sight_range", "spatial_smooth", "temporal_smooth",
    "true_scanlines", "virtual_camera_matrix",
]
