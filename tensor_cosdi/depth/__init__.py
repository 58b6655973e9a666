"""Depth from structured light, light-field views and focal stacks (SPEC §7).

* Structured light: :func:`wrapped_phase` (N-step least squares, Eq. 19), :func:`fringe_modulation`,
  :func:`heterodyne_unwrap` / :func:`temporal_unwrap` (Eq. 22-24), :func:`decode_gray_code` +
  :func:`unwrap_gray_code`, :func:`spatial_unwrap` (scikit-image), :func:`phase_to_height`,
  :func:`calibrate_phase_to_height`.
* Light field: :func:`disparity_from_views` (occlusion-aware cost volume, guided-filter
  aggregation, sub-pixel), :func:`occlusion_cost_volume`, :func:`guided_filter`,
  :func:`depth_from_disparity`.
* Focus: :func:`depth_from_focus`, :func:`focus_measure`.
* :func:`depth_from_cube` — the depth channel of any system's reconstructed cube (``Result.depth``).
"""

from .focus import depth_from_focus, focus_measure
from .from_cube import depth_from_cube
from .light_field import (
    DISPARITY_METHODS,
    depth_from_disparity,
    disparity_cost_volume,
    disparity_from_views,
    guided_filter,
    occlusion_cost_volume,
    textured_mask,
)
from .structured_light import (
    calibrate_phase_to_height,
    decode_gray_code,
    fringe_modulation,
    heterodyne_unwrap,
    phase_to_height,
    spatial_unwrap,
    temporal_unwrap,
    unwrap_gray_code,
    wrap,
    wrapped_phase,
)

__all__ = [
    "wrapped_phase",
    "fringe_modulation",
    "heterodyne_unwrap",
    "temporal_unwrap",
    "decode_gray_code",
    "unwrap_gray_code",
    "spatial_unwrap",
    "phase_to_height",
    "calibrate_phase_to_height",
    "wrap",
    "disparity_from_views",
    "disparity_cost_volume",
    "occlusion_cost_volume",
    "guided_filter",
    "DISPARITY_METHODS",
    "depth_from_disparity",
    "textured_mask",
    "depth_from_focus",
    "focus_measure",
    "depth_from_cube",
]
