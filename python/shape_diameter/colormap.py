# SPDX-License-Identifier: GPL-3.0-or-later
"""SDF values in [0, 1] to RGBA colours through viridis, with numpy alone.

The command line and the Blender add-on both colour meshes with this, and the
add-on must not pull in matplotlib, so viridis is embedded as a table.
"""

from __future__ import annotations

import numpy as np

# Matplotlib's viridis (van der Walt, Smith and Firing, CC0), entries 0, 5, 10, ...,
# 255 of its 256-entry table, so entry i sits at 5*i/255. Linear interpolation
# between them stays within 0.62/255 of the full table in every channel.
# fmt: off
_VIRIDIS = np.array(
    [
        (0.267004, 0.004874, 0.329415), (0.273809, 0.031497, 0.358853),
        (0.278791, 0.062145, 0.386592), (0.281924, 0.089666, 0.412415),
        (0.283197, 0.115680, 0.436115), (0.282623, 0.140926, 0.457517),
        (0.280255, 0.165693, 0.476498), (0.276194, 0.190074, 0.493001),
        (0.270595, 0.214069, 0.507052), (0.263663, 0.237631, 0.518762),
        (0.255645, 0.260703, 0.528312), (0.246811, 0.283237, 0.535941),
        (0.237441, 0.305202, 0.541921), (0.227802, 0.326594, 0.546532),
        (0.218130, 0.347432, 0.550038), (0.208623, 0.367752, 0.552675),
        (0.199430, 0.387607, 0.554642), (0.190631, 0.407061, 0.556089),
        (0.182256, 0.426184, 0.557120), (0.174274, 0.445044, 0.557792),
        (0.166617, 0.463708, 0.558119), (0.159194, 0.482237, 0.558073),
        (0.151918, 0.500685, 0.557587), (0.144759, 0.519093, 0.556572),
        (0.137770, 0.537492, 0.554906), (0.131172, 0.555899, 0.552459),
        (0.125394, 0.574318, 0.549086), (0.121148, 0.592739, 0.544641),
        (0.119423, 0.611141, 0.538982), (0.121380, 0.629492, 0.531973),
        (0.128087, 0.647749, 0.523491), (0.140210, 0.665859, 0.513427),
        (0.157851, 0.683765, 0.501686), (0.180653, 0.701402, 0.488189),
        (0.208030, 0.718701, 0.472873), (0.239374, 0.735588, 0.455688),
        (0.274149, 0.751988, 0.436601), (0.311925, 0.767822, 0.415586),
        (0.352360, 0.783011, 0.392636), (0.395174, 0.797475, 0.367757),
        (0.440137, 0.811138, 0.340967), (0.487026, 0.823929, 0.312321),
        (0.535621, 0.835785, 0.281908), (0.585678, 0.846661, 0.249897),
        (0.636902, 0.856542, 0.216620), (0.688944, 0.865448, 0.182725),
        (0.741388, 0.873449, 0.149561), (0.793760, 0.880678, 0.120005),
        (0.845561, 0.887322, 0.099702), (0.896320, 0.893616, 0.096335),
        (0.945636, 0.899815, 0.112838), (0.993248, 0.906157, 0.143936),
    ]
)
# fmt: on
_POSITIONS = np.linspace(0.0, 1.0, len(_VIRIDIS))
# np.interp's own terms, computed once: the slope of each interval (the last, a point, 0),
# so that colormap() gives its results bit for bit with one index for all three channels.
_SLOPES = np.vstack([np.diff(_VIRIDIS, axis=0) / np.diff(_POSITIONS)[:, None], np.zeros(3)])

# Values that are not numbers (no valid SDF) get a grey outside the map, so they
# cannot be mistaken for any diameter.
NAN_RGBA = (128, 128, 128, 255)


def colormap(values) -> np.ndarray:
    """Map values to (k, 4) uint8 RGBA, k = number of values (any input shape is flattened).

    Values are clipped to [0, 1]; 0 is dark purple, 1 yellow; NaN is NAN_RGBA.
    """
    values = np.asarray(values, dtype=np.float64).reshape(-1)
    missing = np.isnan(values)
    position = np.clip(np.where(missing, 0.0, values), 0.0, 1.0)
    rgb = _interpolate(position)
    rgba = np.empty((len(values), 4), dtype=np.uint8)
    rgba[:, :3] = np.rint(rgb * 255.0)
    rgba[:, 3] = 255
    rgba[missing] = NAN_RGBA
    return rgba


def _interpolate(position: np.ndarray) -> np.ndarray:
    """(k, 3) viridis at positions in [0, 1]: np.interp's arithmetic (slope * (x - x_j) + y_j
    on the interval [x_j, x_j+1) that holds x; y_j itself at the last knot), bit for bit, at a
    fifth of its time on a million values (np.interp searches the knots once per channel)."""
    last = len(_POSITIONS) - 1
    # The knots are evenly spaced: the index from a product, then set right where rounding
    # put it one off (the knot at or below x, as np.interp's search finds it).
    index = np.minimum((position * last).astype(np.intp), last)
    index -= _POSITIONS[index] > position
    index += (index < last) & (_POSITIONS[np.minimum(index + 1, last)] <= position)
    offset = (position - _POSITIONS[index])[:, None]
    return _SLOPES[index] * offset + _VIRIDIS[index]


# A qualitative palette for segments: ColorBrewer's Set3 and Dark2 (Cynthia Brewer, Apache
# 2.0), 20 colours that neighbouring labels tell apart; labels past 20 reuse them in turn.
# fmt: off
_SEGMENT_PALETTE = np.array(
    [
        (141, 211, 199), (27, 158, 119), (255, 255, 179), (217, 95, 2), (190, 186, 218),
        (117, 112, 179), (251, 128, 114), (231, 41, 138), (128, 177, 211), (102, 166, 30),
        (253, 180, 98), (230, 171, 2), (179, 222, 105), (166, 118, 29), (252, 205, 229),
        (102, 102, 102), (217, 217, 217), (188, 128, 189), (204, 235, 197), (255, 237, 111),
    ],
    dtype=np.uint8,
)
# fmt: on


def segment_colors(labels) -> np.ndarray:
    """Map integer segment labels (>= 0) to (k, 4) uint8 RGBA from a qualitative palette."""
    labels = np.asarray(labels, dtype=np.int64).ravel()
    rgba = np.full((labels.size, 4), 255, dtype=np.uint8)
    rgba[:, :3] = _SEGMENT_PALETTE[labels % len(_SEGMENT_PALETTE)]
    return rgba
