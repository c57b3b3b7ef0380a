# SPDX-License-Identifier: GPL-3.0-or-later
"""The one module of the add-on that talks to the `shape_diameter` package (the native core).

The package is imported lazily, on first use, never at register(): a core that cannot load
(a missing system library, a wheel for another Python) must not stop the add-on from
registering, nor take Blender down. The load error is kept and shown in the panel and the
preferences, and every operator run reports it.

Nothing here touches bpy, so the functions below are safe on the worker thread.
"""

import inspect

import numpy as np

_module = None
_load_error = None
_engines = None


class CoreUnavailable(RuntimeError):
    """The native package could not be imported."""


def load():
    """The `shape_diameter` package, imported on first use; raises CoreUnavailable."""
    global _module, _load_error
    if _module is not None:
        return _module
    try:
        import shape_diameter
        import shape_diameter.colormap
    except Exception as ex:  # ImportError, OSError from the dynamic loader, anything
        _load_error = f"{type(ex).__name__}: {ex}"
        raise CoreUnavailable(f"The Shape Diameter core could not be loaded: {_load_error}") from ex
    _module = shape_diameter
    _load_error = None
    return _module


def status():
    """(loaded, text) for the UI: the package version, or why it could not be loaded."""
    try:
        sd = load()
    except CoreUnavailable:
        return False, _load_error
    return True, f"shape_diameter {getattr(sd, '__version__', '?')}"


def engines(refresh=False):
    """The engines the core offers here (dicts with at least 'name'), best first; [] when the
    core cannot load. Cached: the core may probe devices, and enum callbacks run on redraw."""
    global _engines
    if _engines is None or refresh:
        try:
            _engines = list(load().engines())
        except CoreUnavailable:
            return []
    return _engines


def supports(option):
    """Whether shape_diameter.compute() accepts the keyword `option` (features such as
    smoothing or accel appear in the UI only once the core has them)."""
    try:
        return option in inspect.signature(load().compute).parameters
    except CoreUnavailable:
        return False


def compute(vertices, triangles, options, progress=None, uvs=None):
    """shape_diameter.compute on one triangle mesh. `options` holds compute()'s keywords
    (rays, cone_angle, sampling, seed, points, normalize, engine, accel, smoothing, ...);
    `uvs` (m, 3, 2) per triangle corner, for texture smoothing; `progress` is called with the
    fraction done and may raise to cancel."""
    if uvs is not None and options.get("smoothing") == "texture":
        options = dict(options, uvs=uvs)
    return load().compute(vertices, triangles, progress=progress, **options)


def normalize(values, method):
    """The core's normalisation ('linear' or 'log') of a field to [0, 1]."""
    return load().normalize(values, method)


def colors(normalized):
    """(k, 4) float32 sRGB colours in [0, 1] from the core's perceptual colour map."""
    rgba = load().colormap.colormap(normalized)
    return rgba.astype("float32") / 255.0


def has(name):
    """Whether the package has the function `name` (e.g. 'smooth'); False if it cannot load."""
    try:
        return callable(getattr(load(), name, None))
    except CoreUnavailable:
        return False


def collect_warnings():
    """A context manager: the core's warnings raised inside, on this thread, go into the list
    it gives instead of being printed (shape_diameter.collect_warnings: unlike
    warnings.catch_warnings, safe on the add-on's worker thread)."""
    return load().collect_warnings()


def cpu_threads():
    """The threads the CPU engine runs on here (shape_diameter.engines()' 'cpu' entry)."""
    cpu = [e for e in engines() if e["name"] == "cpu"]
    return int(cpu[0].get("threads") or 1) if cpu else 1


def texture_cost(size, radius, uvs):
    """The core's own estimate of texture smoothing (and a bake's drawing and blur) at `size`
    texels square and `radius` (None: the core's default), known before running it:
    shape_diameter.smoothing.texture_cost (texels, blur_reads, bytes)."""
    return load().smoothing.texture_cost(int(size), radius, uvs)


def default_radius(size):
    """Texture smoothing's default blur radius in texels at `size` texels square."""
    return load().smoothing.default_radius(int(size))


def uv_layout(vertices, triangles, uvs, points, for_images):
    """shape_diameter.uv_layout: the UV layout (UDIM tiles, overlapping shells) that texture
    smoothing and the bake take (found once); its `warnings` say what it is, worded for
    images where `for_images`."""
    return load().uv_layout(vertices, triangles, uvs, points=points, return_image=for_images)


def bake(
    vertices,
    triangles,
    values,
    points,
    uvs,
    size,
    radius,
    margin,
    progress=None,
    engine="auto",
    threads=0,
    uv_layout=None,
):
    """The field rasterised through per-corner uvs (m, 3, 2) into (size, size) float32
    images in Blender's pixel order (row 0 at v = 0), one per UDIM tile the UVs use (a dict
    tile number -> image, tile 1001 always, empty where no face lies in it): the value where
    a face (or the margin around an island) covers the texel, else 0. `radius` is the
    texture-space blur in texels (0: none, None: the core's default). Rasterising and
    blurring are the core's (shape_diameter.smooth(..., 'texture', return_image=True)), on
    `engine` (compute()'s names) with `threads` CPU threads (0: every core); `uv_layout`:
    what uv_layout() found for these UVs and points, or None."""
    layout = {} if uv_layout is None else {"uv_layout": uv_layout}
    out = load().smooth(
        vertices,
        triangles,
        values,
        "texture",
        uvs=uvs,
        points=points,
        progress=progress,
        engine=engine,
        threads=threads,
        texture_size=int(size),
        radius=radius,
        margin=int(margin),
        return_image=True,
        **layout,
    )
    tiles = {number: image for number, (image, _) in out.tiles.items()}
    tiles.setdefault(1001, np.zeros_like(out.image))
    return dict(sorted(tiles.items()))


def segment(vertices, triangles, values, options, progress=None):
    """shape_diameter.segment on one triangle mesh from per-triangle values; `options` holds
    segment()'s keywords (clusters, smoothness, mode, ...); `progress` is called with the
    fraction done and may raise to stop the segmentation itself."""
    return load().segment(vertices, triangles, values, progress=progress, **options)


def segment_colors(labels):
    """(k, 4) float32 sRGB colours in [0, 1], one qualitative colour per segment label."""
    import shape_diameter.colormap

    return shape_diameter.colormap.segment_colors(labels).astype("float32") / 255.0


def rigging():
    """The package's bpy-free rigging module (polygon labels, principal axes, skeleton)."""
    load()
    import shape_diameter.rigging

    return shape_diameter.rigging
