# SPDX-License-Identifier: GPL-3.0-or-later
"""What a glTF/GLB file asks of its reader that trimesh does not do, refused up front.

trimesh reads such files without a word and gives wrong geometry: a Draco-compressed
primitive as zeros, KHR_mesh_quantization's normalized integers as raw integers (32767 times
too large), a sparse accessor's base values only, triangle fans not at all, and a mesh on a
camera node not at all; each of these was computed with status 'ok', the values wrong.
"""

from __future__ import annotations

# Required extensions that leave positions and indices as core glTF stores them.
_HARMLESS_PREFIXES = ("KHR_materials_", "KHR_texture_", "EXT_texture_", "KHR_lights_")
_TRIANGLE_FAN = 6


def check_gltf(header: dict, uvs: bool = False) -> None:
    """Raises ValueError naming the first feature of the file that would be read wrongly
    (its UVs only with `uvs`: they matter to texture smoothing alone)."""
    required = [
        name
        for name in header.get("extensionsRequired", [])
        if not str(name).startswith(_HARMLESS_PREFIXES)
    ]
    if required:
        raise ValueError(
            f"it requires the glTF extension{'s' if len(required) > 1 else ''} "
            f"{', '.join(map(str, required))}, which this reader does not decode "
            "(export without mesh compression or quantization)"
        )
    accessors = header.get("accessors", [])
    for m, mesh in enumerate(header.get("meshes", [])):
        for p, primitive in enumerate(mesh.get("primitives", [])):
            where = f"mesh {m} primitive {p}"
            if primitive.get("mode", 4) == _TRIANGLE_FAN:
                raise ValueError(f"{where} is a triangle fan (mode 6), which this reader drops")
            attributes = primitive.get("attributes", {})
            for name in ("POSITION", "TEXCOORD_0") if uvs else ("POSITION",):
                index = attributes.get(name)
                if not isinstance(index, int) or not 0 <= index < len(accessors):
                    continue
                accessor = accessors[index]
                if accessor.get("normalized"):
                    raise ValueError(
                        f"{where}'s {name} is stored as normalized integers, which "
                        "this reader takes as plain integers"
                    )
                if "sparse" in accessor:
                    raise ValueError(
                        f"{where}'s {name} is a sparse accessor, whose changes "
                        "this reader leaves out"
                    )
    for n, node in enumerate(header.get("nodes", [])):
        if "camera" in node and ("mesh" in node or node.get("children")):
            raise ValueError(
                f"node {n} is a camera holding a mesh or children, which this reader leaves out"
            )
