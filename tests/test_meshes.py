"""Meshes (wgpuviewer.meshes): the curved builtins' analytic frames and seams; tangents from uv derivatives and from
a glTF's TANGENT; glTF (.glb, .gltf with an external image) and OBJ (+ .mtl + image) files generated here (trimesh
exports them, or a few lines of JSON), read with their own textures, cached, and every bad file refused in one line
naming the scene key."""

from __future__ import annotations

import base64
import io
import json
import logging
import os
from pathlib import Path

import numpy as np
import PIL.Image
import pytest
import trimesh

from wgpuviewer import meshes
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.images import ImageBytes
from wgpuviewer.scene import load_scene

# --- curved builtins ---------------------------------------------------------------------------

CURVED = {"sphere": (0.7,), "cylinder": (0.5, 1.5), "torus": (1.0, 0.3)}


def analytic_normals(kind: str, size, p: np.ndarray) -> np.ndarray:
    """The shape's exact outward normals at the points ``p``."""
    if kind == "sphere":
        return p / size[0]
    radial = p * [1, 0, 1]
    radial /= np.maximum(np.linalg.norm(radial, axis=1, keepdims=True), 1e-30)
    if kind == "torus":
        return (p - size[0] * radial) / size[1]
    # a cylinder's cap: the triangles whose three corners are on one of its ends
    cap = np.repeat(np.isclose(p[:, 1].reshape(-1, 3), p[::3, 1:2]).all(axis=1), 3)
    return np.where(cap[:, None], [[0.0, 1.0, 0.0]] * np.sign(p[:, 1:2]), radial)


@pytest.mark.parametrize("kind", CURVED)
def test_curved_builtins_have_analytic_unit_frames_and_front_faces_outside(kind):
    size = CURVED[kind]
    v = meshes.build(kind, size).astype(np.float64)
    p, n, t, w, uv = v[:, :3], v[:, 3:6], v[:, 6:9], v[:, 9], v[:, 10:]
    assert np.allclose(np.linalg.norm(t, axis=1), 1, atol=1e-6)
    assert np.allclose(np.linalg.norm(n, axis=1), 1, atol=1e-6)
    assert np.abs(np.einsum("ij,ij->i", t, n)).max() < 1e-6
    assert np.allclose(n, analytic_normals(kind, size, p), atol=1e-5)
    assert set(np.unique(w)) == {-1.0}  # one handedness: u right and v down seen from outside, as on a quad
    assert uv.min() == 0 and uv.max() == 1
    tri = p.reshape(-1, 3, 3)
    face = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert (np.einsum("ij,ij->i", face, n.reshape(-1, 3, 3).mean(axis=1)) > 0).all()  # counter-clockwise outside
    # the bitangent w * (n x t) runs along +v: each triangle's dP/dv from its own corners agrees with it
    d_p = np.stack([tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0]], 1)
    d_uv = np.stack([uv.reshape(-1, 3, 2)[:, 1] - uv.reshape(-1, 3, 2)[:, 0],
                     uv.reshape(-1, 3, 2)[:, 2] - uv.reshape(-1, 3, 2)[:, 0]], 1)
    solvable = np.abs(np.linalg.det(d_uv)) > 1e-12
    dp_duv = np.linalg.solve(d_uv[solvable], d_p[solvable])  # rows: dP/du, dP/dv
    bitangent = (w[:, None] * np.cross(n, t)).reshape(-1, 3, 3).mean(axis=1)[solvable]
    assert (np.einsum("ij,ij->i", dp_duv[:, 1], bitangent) > 0).all()
    assert (np.einsum("ij,ij->i", dp_duv[:, 0], t.reshape(-1, 3, 3).mean(axis=1)[solvable]) > 0).all()


@pytest.mark.parametrize("kind", CURVED)
def test_curved_seams_have_their_own_vertices_at_the_same_positions(kind):
    v = meshes.build(kind, CURVED[kind])
    side = v[np.abs(v[:, 4]) < 1]  # not a pole, not a cylinder's cap
    start = {row[11]: tuple(row[:3]) for row in side[side[:, 10] == 0.0]}
    seam = side[side[:, 10] == 1.0]
    assert len(seam) and all(start[row[11]] == tuple(row[:3]) for row in seam)  # bit-identical: no crack


# --- tangents ---------------------------------------------------------------------------------

QUAD_POSITIONS = np.array([[-1, 1, 0], [-1, -1, 0], [1, -1, 0], [1, 1, 0]], np.float64)
QUAD_UV = np.array([[0, 0], [0, 1], [1, 1], [1, 0]], np.float64)  # v = 0 at the top (image row 0)
QUAD_FACES = np.array([[0, 1, 2], [0, 2, 3]])


def test_generated_tangents_are_the_builtin_quads():
    corners = meshes.corner_vertices(Path("q"), "quad", QUAD_POSITIONS, QUAD_UV, QUAD_FACES)
    assert np.allclose(corners, meshes.quad(2, 2), atol=1e-7)


def test_generated_handedness_follows_mirrored_uvs():
    mirrored = QUAD_UV * [-1, 1] + [1, 0]  # u runs right to left
    corners = meshes.corner_vertices(Path("q"), "quad", QUAD_POSITIONS, mirrored, QUAD_FACES)
    assert np.allclose(corners[:, 6:9], [[-1, 0, 0]]) and (corners[:, 9] == 1).all()


def test_generated_tangents_of_a_sphere_match_its_analytic_ones():
    """Tangents summed over the triangles around each indexed vertex (away from the poles and the seam, where
    MikkTSpace-like sums are exact up to tessellation) follow the analytic tangent within a degree."""
    nu, nv = meshes.SPHERE_GRID
    u, v = np.meshgrid(np.arange(nu + 1) / nu, np.arange(nv + 1) / nv, indexing="ij")
    phi, theta = 2 * np.pi * u.ravel(), np.pi * v.ravel()
    p = np.stack([np.sin(theta) * np.sin(phi), np.cos(theta), np.sin(theta) * np.cos(phi)], 1)
    idx = np.arange(len(p)).reshape(nu + 1, nv + 1)
    a, b, c, d = idx[:-1, :-1], idx[:-1, 1:], idx[1:, 1:], idx[1:, :-1]
    faces = np.concatenate([np.stack([a, b, c], -1).reshape(-1, 3), np.stack([a, c, d], -1).reshape(-1, 3)])
    tangent, w = meshes.vertex_tangents(p, np.stack([u.ravel(), v.ravel()], 1), faces)
    inner = (v.ravel() > 0.1) & (v.ravel() < 0.9) & (u.ravel() > 0) & (u.ravel() < 1)
    expected = np.stack([np.cos(phi), 0 * phi, -np.sin(phi)], 1)[inner]
    got = tangent[inner] / np.linalg.norm(tangent[inner], axis=1, keepdims=True)
    assert np.degrees(np.arccos(np.clip(np.einsum("ij,ij->i", got, expected), -1, 1))).max() < 1.0
    assert (w[inner] == -1).all()


# --- files ------------------------------------------------------------------------------------

RED_BLUE = np.zeros((16, 16, 3), np.uint8)
RED_BLUE[:8, :, 0] = 255  # top rows red: v < 0.5
RED_BLUE[8:, :, 2] = 255


def textured_quad() -> trimesh.Trimesh:
    """The 2x2 quad facing +Z with the red-over-blue image; trimesh keeps uvs with v up (OpenGL), so v is flipped."""
    material = trimesh.visual.material.PBRMaterial(name="red_blue", baseColorTexture=PIL.Image.fromarray(RED_BLUE))
    uv = QUAD_UV * [1, -1] + [0, 1]
    return trimesh.Trimesh(QUAD_POSITIONS, QUAD_FACES, process=False,
                           visual=trimesh.visual.TextureVisuals(uv=uv, material=material))


def write_glb(path: Path) -> Path:
    scene = trimesh.Scene()
    scene.add_geometry(textured_quad(), node_name="panel", geom_name="panel")
    path.write_bytes(scene.export(file_type="glb"))
    return path


def write_gltf_external_png(folder: Path) -> Path:
    """A .gltf whose buffers are .bin files and whose image is an external albedo.png."""
    files = trimesh.Scene(textured_quad()).export(file_type="gltf")
    doc = json.loads(files.pop("model.gltf"))
    doc["images"] = [{"uri": "albedo.png"}]
    for name, data in files.items():
        (folder / name).write_bytes(data)
    PIL.Image.fromarray(RED_BLUE).save(folder / "albedo.png")
    (folder / "panel.gltf").write_text(json.dumps(doc))
    return folder / "panel.gltf"


def write_obj(folder: Path) -> Path:
    text, textures = trimesh.exchange.obj.export_obj(textured_quad(), include_texture=True, return_texture=True,
                                                      mtl_name="panel.mtl")
    for name, data in textures.items():
        (folder / name).write_bytes(data)
    (folder / "panel.obj").write_text(text)
    return folder / "panel.obj"


def write_gltf(path: Path, positions, uv=None, faces=None, normals=None, tangents=None, mode=4, nodes=None,
               image_uri=None, extra_accessor=None) -> Path:
    """A minimal .gltf with one data-URI buffer; ``nodes``: [(name, translation)] each showing the mesh."""
    arrays = {"POSITION": positions, "TEXCOORD_0": uv, "NORMAL": normals, "TANGENT": tangents}
    blob, views, accessors, attributes = b"", [], [], {}
    for name, data in [*arrays.items(), ("indices", faces)]:
        if data is None:
            continue
        data = np.asarray(data, np.uint32 if name == "indices" else np.float32)
        types = {1: "SCALAR", 2: "VEC2", 3: "VEC3", 4: "VEC4"}
        views.append({"buffer": 0, "byteOffset": len(blob), "byteLength": data.nbytes})
        accessors.append({"bufferView": len(views) - 1, "componentType": 5125 if name == "indices" else 5126,
                          "count": int(data.size if name == "indices" else len(data)),
                          "type": "SCALAR" if name == "indices" else types[data.shape[1]], **(extra_accessor or {})})
        blob += data.tobytes()
        if name != "indices":
            attributes[name] = len(accessors) - 1
    primitive = {"attributes": attributes, "mode": mode}
    if faces is not None:
        primitive["indices"] = len(accessors) - 1
    doc = {"asset": {"version": "2.0"}, "buffers": [{"byteLength": len(blob), "uri": "data:application/octet-stream;"
                                                     "base64," + base64.b64encode(blob).decode()}],
           "bufferViews": views, "accessors": accessors, "meshes": [{"primitives": [primitive]}],
           "nodes": [{"name": n, "mesh": 0, "translation": list(t)} for n, t in (nodes or [("quad", (0, 0, 0))])]}
    doc["scenes"], doc["scene"] = [{"nodes": list(range(len(doc["nodes"])))}], 0
    if image_uri is not None:
        doc["images"] = [{"uri": image_uri}]
        doc["textures"] = [{"source": 0}]
        doc["materials"] = [{"pbrMetallicRoughness": {"baseColorTexture": {"index": 0}}}]
        primitive["material"] = 0
    path.write_text(json.dumps(doc))
    return path


def mesh_scene(folder: Path, file: str, extra: str = "", material: str | None = None) -> Path:
    lines = ["[camera]", "position = [0.0, 0.0, 4.0]", "target = [0.0, 0.0, 0.0]",
             "[materials.bricks]", 'albedo = "builtin:bricks"', 'height = "builtin:bricks"',
             "[[objects]]", 'type = "mesh"', f"file = {json.dumps(file)}", extra]
    if material:
        lines.append(f'material = "{material}"')
    path = folder / "scene.toml"
    path.write_text("\n".join(lines) + "\n")
    return path


@pytest.fixture(autouse=True)
def fresh_cache():
    meshes.clear_cache()
    yield
    meshes.clear_cache()


def pixels(ref) -> np.ndarray:
    """The RGB pixels of a file texture: a file, or the bytes of an image a glTF embeds."""
    source = io.BytesIO(ref.path.data) if isinstance(ref.path, ImageBytes) else ref.path
    return np.asarray(PIL.Image.open(source).convert("RGB"))


def top_left_v(vertices: np.ndarray) -> float:
    """v of the quad's top-left corner (-1, 1, 0)."""
    at = np.all(np.isclose(vertices[:, :3], [-1, 1, 0]), axis=1)
    return float(vertices[at][0, 11])


@pytest.mark.parametrize("writer", [lambda d: write_glb(d / "panel.glb"), write_gltf_external_png, write_obj],
                         ids=["glb", "gltf+png", "obj+mtl+png"])
def test_files_load_with_their_own_albedo_and_image_rows_at_v0(tmp_path, writer):
    path = writer(tmp_path)
    scene = load_scene(mesh_scene(tmp_path, path.name))
    obj = scene.objects[0]
    material = scene.materials[obj.material]
    assert obj.type == "mesh" and obj.file == path and material.albedo.kind == "file"
    assert np.array_equal(pixels(material.albedo), RED_BLUE)
    if path.suffix != ".glb":
        assert material.albedo.path.parent == tmp_path  # the file next to the mesh, not a copy
    else:  # the GLB's own bytes, read from memory: no temporary file
        assert isinstance(material.albedo.path, ImageBytes) and str(material.albedo.path).endswith("images[0]")
    vertices = meshes.for_object(obj)
    assert len(vertices) == 6 and top_left_v(vertices) == 0.0  # the image's top row at the quad's top
    assert np.allclose(vertices[:, 3:10], meshes.quad(2, 2)[:, 3:10])  # +Z normal, tangent +X, w as a quad's
    assert obj.size == (2.0, 2.0, 0.0)


def test_file_normal_and_bump_maps_become_the_materials_normal_and_height(tmp_path):
    normal = np.full((8, 8, 3), (128, 128, 255), np.uint8)
    quad = textured_quad()
    quad.visual.material.normalTexture = PIL.Image.fromarray(normal)
    trimesh.Scene(quad).export(tmp_path / "n.glb")
    glb = load_scene(mesh_scene(tmp_path, "n.glb"))
    material = glb.materials[glb.objects[0].material]
    assert material.normal.kind == "file" and material.height is None and material.normal_y == "opengl"
    assert np.array_equal(pixels(material.normal), normal)
    obj = write_obj(tmp_path)
    PIL.Image.fromarray(RED_BLUE[..., 0]).save(tmp_path / "bump.png")
    mtl = tmp_path / "panel.mtl"
    mtl.write_text(mtl.read_text() + "\nbump -bm 1.0 bump.png\n")
    scene = load_scene(mesh_scene(tmp_path, obj.name))
    height = scene.materials[scene.objects[0].material].height
    assert height.kind == "file" and height.path == tmp_path / "bump.png"


def test_a_scene_material_replaces_the_files(tmp_path):
    write_glb(tmp_path / "panel.glb")
    scene = load_scene(mesh_scene(tmp_path, "panel.glb", material="bricks"))
    assert scene.objects[0].material == "bricks" and set(scene.materials) == {"bricks"}


def test_gltf_tangents_are_read_with_gltfs_handedness_turned_to_ours(tmp_path):
    """glTF's TANGENT w makes the bitangent point to image row 0 (+Y of its normal maps); ours points to +v."""
    tangents = np.tile([1.0, 0.0, 0.0, 1.0], (4, 1))
    path = write_gltf(tmp_path / "t.gltf", QUAD_POSITIONS, QUAD_UV, QUAD_FACES, normals=np.tile([0, 0, 1.0], (4, 1)),
                      tangents=tangents)
    mesh = meshes.load_mesh(path)
    assert mesh.file_tangents and np.allclose(mesh.vertices, meshes.quad(2, 2))
    generated = meshes.load_mesh(write_gltf(tmp_path / "g.gltf", QUAD_POSITIONS, QUAD_UV, QUAD_FACES))
    assert not generated.file_tangents and np.allclose(generated.vertices, meshes.quad(2, 2))


def test_nodes_place_their_meshes_and_node_picks_one(tmp_path):
    path = write_gltf(tmp_path / "two.gltf", QUAD_POSITIONS, QUAD_UV, QUAD_FACES,
                      nodes=[("left", (-3, 0, 0)), ("right", (3, 0, 0))])
    assert len(meshes.load_mesh(path).vertices) == 12
    right = meshes.load_mesh(path, "right")
    assert len(right.vertices) == 6 and np.allclose(right.vertices[:, 0].min(), 2.0)
    assert right.names == ("left", "right")


def test_obj_objects_are_nodes(tmp_path):
    """An OBJ's ``o`` objects are what ``node`` picks; vt counts from the image's bottom row."""
    quad = "v -1 1 0\nv -1 -1 0\nv 1 -1 0\nv 1 1 0\nvt 0 1\nvt 0 0\nvt 1 0\nvt 1 1\n"
    text = "o left\n" + quad + "f 1/1 2/2 3/3 4/4\no right\n" + quad.replace("v 1", "v 3").replace("v -1", "v 1") \
        + "f 5/5 6/6 7/7 8/8\n"
    (tmp_path / "two.obj").write_text(text)
    both = meshes.load_mesh(tmp_path / "two.obj")
    right = meshes.load_mesh(tmp_path / "two.obj", "right")
    assert both.names == ("left", "right") and len(both.vertices) == 12 and len(right.vertices) == 6
    assert np.allclose(right.vertices[:, 3:6], [0, 0, 1])  # the quads split counter-clockwise, as written
    assert right.vertices[:, 0].min() == 1.0 and top_left_v(meshes.load_mesh(tmp_path / "two.obj", "left").vertices) == 0
    with pytest.raises(meshes.NodeNotFound, match="no object named 'middle' in two.obj; its objects: left, right"):
        meshes.load_mesh(tmp_path / "two.obj", "middle")


def test_scale_and_mirroring_keep_frames_and_front_faces(tmp_path):
    v = meshes.transformed(meshes.sphere(1.0), np.diag([2.0, 1.0, -0.5]))
    p, n, t = v[:, :3], v[:, 3:6], v[:, 6:9]
    expected = p / np.array([2.0, 1.0, -0.5]) ** 2  # the ellipsoid's gradient
    assert np.allclose(n, expected / np.linalg.norm(expected, axis=1, keepdims=True), atol=1e-5)
    assert np.abs(np.einsum("ij,ij->i", n, t)).max() < 1e-9
    tri = p.reshape(-1, 3, 3)
    face = np.cross(tri[:, 1] - tri[:, 0], tri[:, 2] - tri[:, 0])
    assert (np.einsum("ij,ij->i", face, n.reshape(-1, 3, 3).mean(axis=1)) > 0).all()
    assert set(np.unique(v[:, 9])) == {1.0}  # the mirror turned the handedness


def test_meshes_are_read_once_per_file_and_again_when_it_changes(tmp_path):
    path = write_glb(tmp_path / "panel.glb")
    first = meshes.load_mesh(path)
    assert meshes.load_mesh(path) is first
    os.utime(path, ns=(path.stat().st_atime_ns, path.stat().st_mtime_ns + 10**9))
    assert meshes.load_mesh(path) is not first


def test_zero_area_triangles_are_dropped_with_a_warning(tmp_path, caplog):
    positions = np.concatenate([QUAD_POSITIONS, [[0, 0, 0], [0, 0, 0], [1, 1, 0]]])
    uv = np.concatenate([QUAD_UV, [[0, 0], [1, 0], [0, 1]]])
    faces = np.concatenate([QUAD_FACES, [[4, 5, 6]]])
    with caplog.at_level(logging.WARNING, "wgpuviewer.meshes"):
        mesh = meshes.load_mesh(write_gltf(tmp_path / "d.gltf", positions, uv, faces))
    assert mesh.dropped == 1 and len(mesh.vertices) == 6
    assert "dropped 1 of 3 triangles with zero area" in caplog.text


GOOD = dict(positions=QUAD_POSITIONS, uv=QUAD_UV, faces=QUAD_FACES)
NAN = QUAD_POSITIONS.copy()
NAN[2, 1] = np.nan


def bad_gltf(name, **changes):
    def write(folder: Path) -> str:
        write_gltf(folder / name, **{**GOOD, **changes})
        return name
    return write


def write_bytes(name: str, data: bytes):
    def write(folder: Path) -> str:
        (folder / name).write_bytes(data)
        return name
    return write


def truncated_glb(folder: Path) -> str:
    data = write_glb(folder / "full.glb").read_bytes()
    (folder / "cut.glb").write_bytes(data[: len(data) // 2])
    return "cut.glb"


def obj_missing_texture(folder: Path) -> str:
    path = write_obj(folder)
    (folder / "red_blue.png").unlink()
    return path.name


BAD_FILES = {
    "no uvs": (bad_gltf("a.gltf", uv=None), ["objects[0].file = 'a.gltf'", "no TEXCOORD_0", "needs uvs"]),
    "nan position": (bad_gltf("a.gltf", positions=NAN), ["positions are NaN or infinite", "index 2"]),
    "all degenerate": (bad_gltf("a.gltf", positions=np.zeros((4, 3))), ["all 2 triangles have zero area"]),
    "points": (bad_gltf("a.gltf", mode=0), ["points are not supported", "expected triangles"]),
    "sparse": (bad_gltf("a.gltf", extra_accessor={"sparse": {}}), ["sparse", "not supported"]),
    "missing image": (bad_gltf("a.gltf", image_uri="gone.png"), ["images[0]", "'gone.png' not found"]),
    "missing obj texture": (obj_missing_texture, ["panel.mtl", "map_kd 'red_blue.png'", "not found"]),
    "malformed accessor": (bad_gltf("a.gltf", extra_accessor={"count": "many"}),
                           ['accessors[0].count = "many": expected an integer']),
    "garbage glb": (write_bytes("a.glb", b"not a mesh at all, just text"), ["not a GLB file"]),
    "broken gltf json": (write_bytes("a.gltf", b"{ nope"), ["not a glTF file"]),
    "truncated glb": (truncated_glb, ["cut.glb", "truncated"]),
    "unsupported type": (write_bytes("a.stl", b"solid x"), ["unsupported mesh file type", ".glb, .gltf, .obj"]),
    "missing file": (lambda folder: "nothing.glb", ["file not found"]),
}


@pytest.mark.parametrize("case", BAD_FILES)
def test_bad_mesh_files_are_one_line_naming_the_key(tmp_path, case):
    make, parts = BAD_FILES[case]
    scene = mesh_scene(tmp_path, make(tmp_path))
    with pytest.raises(UserError) as error:
        load_scene(scene)
    message = str(error.value)
    assert "\n" not in message and message.startswith(f"{scene}: objects[0].file = "), message
    for part in parts:
        assert part in message, message


def test_more_vertices_than_the_limit_are_refused_before_reading(tmp_path, monkeypatch):
    monkeypatch.setattr(meshes.model, "MAX_MESH_VERTICES", 5)
    write_gltf(tmp_path / "a.gltf", **GOOD)
    with pytest.raises(UserError, match=r"6 vertices \(2 triangles\), more than the 5 a mesh may have"):
        load_scene(mesh_scene(tmp_path, "a.gltf"))


@pytest.mark.parametrize("extra, parts", [
    ('node = "middle"', ["objects[0].node = 'middle'", "no node named 'middle'", "its nodes: left, right"]),
    ("size = [1.0, 2.0]", ["objects[0].size", "its size comes from its file", "scale"]),
    ("scale = 0", ["objects[0].scale = 0", "out of range"]),
    ("scale = [1.0, -1.0, 1.0]", ["objects[0].scale", "out of range"]),
])
def test_bad_mesh_keys(tmp_path, extra, parts):
    write_gltf(tmp_path / "two.gltf", **GOOD, nodes=[("left", (-3, 0, 0)), ("right", (3, 0, 0))])
    with pytest.raises(UserError) as error:
        load_scene(mesh_scene(tmp_path, "two.gltf", extra))
    for part in parts:
        assert part in str(error.value), str(error.value)


def test_mesh_keys_on_a_builtin_are_refused(tmp_path):
    path = tmp_path / "s.toml"
    path.write_text('[camera]\nposition = [0, 0, 3]\ntarget = [0, 0, 0]\n[materials.m]\nalbedo = [1, 1, 1]\n'
                    '[[objects]]\ntype = "sphere"\nmaterial = "m"\nsize = [1.0]\nscale = 2\n')
    with pytest.raises(UserError, match=r"objects\[0\].scale = 2: not used by a sphere object"):
        load_scene(path)


def test_render_command_reports_a_bad_mesh_in_one_line(tmp_path, capsys):
    """In this process (the CLI's exit status through its own process: tests/test_mesh_fuzz.py)."""
    from wgpuviewer.cli import main

    scene = mesh_scene(tmp_path, bad_gltf("a.gltf", uv=None)(tmp_path))
    assert main(["render", str(scene), "-o", str(tmp_path / "x.png")]) == 2
    err = capsys.readouterr().err
    lines = [line for line in err.splitlines() if line.startswith("wgpuviewer: error")]
    assert len(lines) == 1 and "no TEXCOORD_0" in lines[0] and "Traceback" not in err
    assert not (tmp_path / "x.png").exists()
