"""Pure-geometry occupancy core: scanlines or discs -> cones -> visual hull -> taskers.

Imports only numpy, scipy, shapely and scikit-learn; never a GL library.
"""

from .checks import check_choice
from .clustering import clustering_select
from .hull import (
    camera_regions_from_discs,
    camera_regions_from_scanlines,
    empty_regions_from_discs,
    empty_regions_from_scanlines,
    free_wedges_from_discs,
    free_wedges_from_scanlines,
    hull_from_wedges,
    polygon_centres,
    prune_small,
    visual_hull_of_discs,
    visual_hull_of_scanlines,
)
from .taskers import (
    TASKERS,
    IncrementalTasker,
    choose_cameras,
    greedy_select,
    incremental_select,
    lazy_greedy_select,
    naive_greedy_select,
    optimal_select,
    uniform_select,
)

__all__ = [
    "TASKERS",
    "IncrementalTasker",
    "camera_regions_from_discs",
    "camera_regions_from_scanlines",
    "check_choice",
    "choose_cameras",
    "clustering_select",
    "empty_regions_from_discs",
    "empty_regions_from_scanlines",
    "free_wedges_from_discs",
    "free_wedges_from_scanlines",
    "greedy_select",
    "hull_from_wedges",
    "incremental_select",
    "lazy_greedy_select",
    "naive_greedy_select",
    "optimal_select",
    "polygon_centres",
    "prune_small",
    "uniform_select",
    "visual_hull_of_discs",
    "visual_hull_of_scanlines",
]
