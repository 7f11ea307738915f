"""Writes the showcase scene's glTF mesh, ``showcase_assets/pillar.gltf``: a turned pillar (plinth, shaft, capital)
as a surface of revolution, u around (from +Z towards +X), v down its profile by arc length (v = 0 at the top),
smooth normals from the profile, no tangents (the loader generates them from the uvs). The file is glTF 2.0 JSON
text with its one buffer as a base64 data URI, so the checkout holds no binary file; this script is its source:
``python scenes/showcase_assets.py`` writes it again, byte for byte."""

from __future__ import annotations

import base64
import json
from pathlib import Path

import numpy as np

#: The profile, top to bottom: (radius, height) in scene units.
PROFILE = [
    (0.0, 2.0), (0.3, 2.0), (0.3, 1.92), (0.25, 1.86), (0.2, 1.8), (0.19, 1.5), (0.2, 1.0), (0.21, 0.5),
    (0.22, 0.3), (0.26, 0.25), (0.28, 0.2), (0.3, 0.15), (0.32, 0.15), (0.32, 0.0), (0.0, 0.0),
]
SEGMENTS = 32


def pillar() -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """positions, normals, uvs and triangle indices of the pillar."""
    profile = np.asarray(PROFILE, np.float64)
    step = np.diff(profile, axis=0)
    length = np.concatenate([[0.0], np.cumsum(np.linalg.norm(step, axis=1))])
    v = length / length[-1]
    # the outward normal of each profile segment going down, (radius, height) = (-d height, d radius), averaged
    # at the points between two segments
    seg = np.stack([-step[:, 1], step[:, 0]], 1)
    seg /= np.linalg.norm(seg, axis=1, keepdims=True)
    point = np.concatenate([seg[:1], seg[:-1] + seg[1:], seg[-1:]])
    point /= np.linalg.norm(point, axis=1, keepdims=True)
    u = np.arange(SEGMENTS + 1) / SEGMENTS
    phi = 2 * np.pi * (u % 1.0)  # the seam's copies evaluated at 0: bit-identical positions
    sin, cos = np.sin(phi)[:, None], np.cos(phi)[:, None]
    radius, height = profile[:, 0][None, :], profile[:, 1][None, :]
    positions = np.stack([radius * sin, np.broadcast_to(height, (SEGMENTS + 1, len(PROFILE))), radius * cos], -1)
    normal_r, normal_y = point[:, 0][None], np.broadcast_to(point[:, 1][None], (SEGMENTS + 1, len(PROFILE)))
    normals = np.stack([normal_r * sin, normal_y, normal_r * cos], -1)
    uv = np.stack(np.meshgrid(u, v, indexing="ij"), -1)
    index = np.arange((SEGMENTS + 1) * len(PROFILE)).reshape(SEGMENTS + 1, len(PROFILE))
    a, b, c, d = index[:-1, :-1], index[:-1, 1:], index[1:, 1:], index[1:, :-1]
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    positions = positions.reshape(-1, 3)
    area = np.linalg.norm(np.cross(*(positions[faces[:, 1:]] - positions[faces[:, :1]]).transpose(1, 0, 2)), axis=1)
    faces = faces[area > 1e-12]  # the quads at the axis are triangles
    return positions, normals.reshape(-1, 3), uv.reshape(-1, 2), faces


def gltf(positions, normals, uv, faces) -> dict:
    arrays = [(positions.astype(np.float32), "VEC3", 5126), (normals.astype(np.float32), "VEC3", 5126),
              (uv.astype(np.float32), "VEC2", 5126), (faces.astype(np.uint16).ravel(), "SCALAR", 5123)]
    blob, views, accessors = b"", [], []
    for data, kind, component in arrays:
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": data.nbytes})
        accessor = {"bufferView": len(views) - 1, "componentType": component, "count": len(data), "type": kind}
        if kind == "VEC3" and not accessors:
            accessor["min"], accessor["max"] = data.min(0).tolist(), data.max(0).tolist()
        accessors.append(accessor)
        blob += data.tobytes() + b"\0" * (-data.nbytes % 4)
    return {
        "asset": {"version": "2.0", "generator": "scenes/showcase_assets.py"},
        "scene": 0, "scenes": [{"nodes": [0]}], "nodes": [{"name": "pillar", "mesh": 0}],
        "meshes": [{"name": "pillar", "primitives": [{"attributes": {"POSITION": 0, "NORMAL": 1, "TEXCOORD_0": 2},
                                                     "indices": 3, "mode": 4}]}],
        "accessors": accessors, "bufferViews": views,
        "buffers": [{"byteLength": len(blob),
                     "uri": "data:application/octet-stream;base64," + base64.b64encode(blob).decode()}],
    }


def main() -> None:
    out = Path(__file__).resolve().parent / "showcase_assets" / "pillar.gltf"
    out.parent.mkdir(exist_ok=True)
    out.write_text(json.dumps(gltf(*pillar()), indent=1) + "\n")
    print(out)


if __name__ == "__main__":
    main()
