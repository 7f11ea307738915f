"""Hostile glTF files (wgpuviewer.meshes.gltf_document, gltf_accessors): every count, offset, stride and index is
checked before an accessor is decoded, and JSON values of the wrong type are named by their key. Each case is one
FileError line naming the file and the key, never a crash, a read outside the buffer or an internal error.

And what valid glTF may hold: KHR_texture_transform (applied to the uvs), a node of scale 0 (its triangles left out),
a material the scene replaces (not read); transforms that push triangles beyond float32 are named as such."""

from __future__ import annotations

import base64
import json
import logging
import os
import struct
import tempfile
import tracemalloc
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.test_meshes import GOOD, QUAD_POSITIONS, QUAD_UV, RED_BLUE, mesh_scene, write_glb, write_gltf
from wgpuviewer import meshes
from wgpuviewer.core.errors import FileError, UserError
from wgpuviewer.core.images import ImageBytes, read_image
from wgpuviewer.meshes import gltf_accessors
from wgpuviewer.scene import load_scene


@pytest.fixture(autouse=True)
def fresh_cache():
    meshes.clear_cache()
    yield
    meshes.clear_cache()


def hostile(folder: Path, change, **kwargs) -> Path:
    """The good quad as a .gltf (one data-URI buffer; bufferViews[0] and accessors[0] are its VEC3 float positions,
    12-byte elements, accessors[2] its indices), its JSON changed by ``change(doc)``."""
    path = write_gltf(folder / "h.gltf", **{**GOOD, **kwargs})
    doc = json.loads(path.read_text())
    change(doc)
    path.write_text(json.dumps(doc))
    return path


def refused(path: Path, *parts: str, node=None) -> str:
    with pytest.raises(FileError) as error:
        meshes.load_mesh(path, node)
    message = str(error.value)
    assert "\n" not in message and message.startswith(f"{path}: "), message
    for part in parts:
        assert part in message, message
    return message


def setter(*keys_and_value):
    """``doc[k1][k2]... = value``."""
    *keys, value = keys_and_value

    def change(doc):
        target = doc
        for key in keys[:-1]:
            target = target[key]
        target[keys[-1]] = value
    return change


@pytest.mark.parametrize("stride", [-1048576, -12, -100000, 1, 0, 8, 253])
def test_a_byte_stride_out_of_range_is_refused_naming_it(tmp_path, stride):
    path = hostile(tmp_path, setter("bufferViews", 0, "byteStride", stride))
    refused(path, f"bufferViews[0].byteStride = {stride}: expected 12 to 252", "accessors[0]")


def test_a_stride_too_wide_for_the_view_is_refused(tmp_path):
    path = hostile(tmp_path, setter("bufferViews", 0, "byteStride", 252))
    refused(path, "accessors[0] reads past the end of its buffer view", "stride 252")


@pytest.mark.parametrize("keys, value, parts", [
    (("bufferViews", 0, "byteOffset"), 10**12, ["bufferViews[0] reads past the end of its buffer"]),
    (("bufferViews", 0, "byteOffset"), -8, ["bufferViews[0].byteOffset = -8: expected 0 or more"]),
    (("bufferViews", 0, "byteLength"), 10**9, ["bufferViews[0] reads past the end of its buffer"]),
    (("bufferViews", 0, "byteLength"), -1, ["bufferViews[0].byteLength = -1: expected 0 or more"]),
    (("accessors", 0, "byteOffset"), 2**40, ["accessors[0] reads past the end of its buffer view"]),
    (("accessors", 0, "byteOffset"), -4, ["accessors[0].byteOffset = -4: expected 0 or more"]),
    (("accessors", 0, "count"), 1000, ["accessors[0] reads past the end of its buffer view"]),
    (("accessors", 0, "count"), 2**40, [f"accessors[0] has {2**40} elements, more than the"]),
    (("accessors", 0, "count"), -1, ["accessors[0].count = -1: expected 0 or more"]),
    (("accessors", 2, "count"), 2**62, [f"{2**62} vertices", "more than the"]),  # the indices: before any is read
    (("accessors", 2, "componentType"), 5126, ["accessors[2] holds triangle indices", "unsigned integers"]),
    (("buffers", 0, "byteLength"), 2**40, [f"buffers[0].byteLength = {2**40}: expected 0 to"]),
    (("buffers", 0, "byteLength"), 10**6, ["buffers[0]:", "fewer than its byteLength 1000000", "truncated"]),
    (("buffers", 0, "uri"), "data:application/octet-stream;base64,abc", ["buffers[0]: its data URI is not valid base64"]),
    (("bufferViews", 0, "buffer"), 3, ["refers to buffers[3], which it does not have"]),
    (("accessors", 0, "bufferView"), -1, ["refers to bufferViews[-1], which it does not have"]),
    (("meshes", 0, "primitives", 0, "attributes", "POSITION"), 99, ["refers to accessors[99]"]),
    (("nodes", 0, "mesh"), 7, ["refers to meshes[7]"]),
    (("accessors", 1, "count"), 3, ["TEXCOORD_0 has 3 elements for 4 positions"]),
])
def test_numbers_beyond_their_buffer_are_refused_naming_the_key(tmp_path, keys, value, parts):
    refused(hostile(tmp_path, setter(*keys, value)), *parts)


def test_indices_outside_the_vertices_are_refused(tmp_path):
    path = write_gltf(tmp_path / "i.gltf", QUAD_POSITIONS, QUAD_UV, np.array([[0, 1, 2], [0, 2, 99]]))
    refused(path, "triangle indices outside its 4 vertices")


def test_a_node_cycle_is_refused(tmp_path):
    def cycle(doc):
        doc["nodes"].append({"name": "loop", "children": [0]})
        doc["nodes"][0]["children"] = [1]
    refused(hostile(tmp_path, cycle), "is reached twice")


@pytest.mark.parametrize("change, parts", [
    (setter("buffers", 0, "uri", 5), ["buffers[0].uri = 5: expected a string"]),
    (setter("buffers", 0, "uri", None), ["buffers[0].uri = null: expected a string"]),
    (setter("asset", "2.0"), ['asset = "2.0": expected an object']),
    (setter("meshes", 0, "primitives", [5]), ["meshes[0].primitives[0] = 5: expected an object"]),
    (setter("meshes", 0, "primitives", 0, "attributes", "POSITION", "0"), ['attributes.POSITION = "0": expected an integer']),
    (setter("accessors", 0, "count", True), ["accessors[0].count = true: expected an integer"]),
    (setter("accessors", 0, "count", 1.5), ["accessors[0].count = 1.5: expected an integer"]),
    (setter("bufferViews", 0, "byteStride", "12"), ['bufferViews[0].byteStride = "12": expected an integer']),
    (setter("nodes", 0, "translation", [1, 2]), ["nodes[0].translation = [1, 2]: expected an array of 3 numbers"]),
    (setter("nodes", 0, "children", 3), ["nodes[0].children = 3: expected an array"]),
    (setter("meshes", 5), ["meshes = 5: expected an array"]),
    (setter("nodes", 0, "matrix", [float("nan")] * 16), ["nodes[0].matrix[0] = NaN: expected a number"]),
    (setter("nodes", 0, "scale", [1e400, 1, 1]), ["nodes[0].scale[0] = Infinity: expected a number"]),
    (lambda doc: doc["accessors"][0].pop("componentType"), ["accessors[0].componentType: missing"]),
])
def test_json_values_of_the_wrong_type_are_named_by_their_key(tmp_path, change, parts):
    refused(hostile(tmp_path, change), *parts)


@pytest.mark.parametrize("change, parts", [
    (setter("images", 0, "uri", 7), ["images[0].uri = 7: expected a string"]),
    (setter("materials", 0, "pbrMetallicRoughness", 5), ["materials[0].pbrMetallicRoughness = 5: expected an object"]),
    (setter("materials", 0, "pbrMetallicRoughness", "baseColorFactor", [1]),
     ["materials[0].pbrMetallicRoughness.baseColorFactor = [1]: expected an array of 4 numbers"]),
    (setter("materials", 0, "pbrMetallicRoughness", "baseColorFactor", [float("nan"), 1, 1, 1]),
     ["materials[0].pbrMetallicRoughness.baseColorFactor[0] = NaN: expected a number"]),
    (setter("textures", 0, "source", 4), ["refers to images[4], which it does not have"]),
    (setter("images", 0, "uri", "data:image/png;base64,iVBORw0KGgo="), ["images[0]", "damaged or truncated PNG"]),
])
def test_material_values_of_the_wrong_type_are_named_by_their_key(tmp_path, change, parts):
    (tmp_path / "albedo.png").write_bytes(cv2.imencode(".png", RED_BLUE)[1].tobytes())
    refused(hostile(tmp_path, change, image_uri="albedo.png"), *parts)


@pytest.mark.parametrize("name", ["EXT_meshopt_compression", "KHR_draco_mesh_compression"])
def test_a_required_extension_we_do_not_implement_is_refused_by_name(tmp_path, name):
    def require(doc):
        doc["extensionsUsed"] = doc["extensionsRequired"] = [name]
    message = refused(hostile(tmp_path, require), f"extensionsRequired names {name}, which is not supported")
    assert "export" in message  # the fix


def test_an_external_buffer_far_larger_than_declared_is_not_read_whole(tmp_path):
    """A .bin of 8 GiB (sparse) under a buffer declaring 180 bytes: only the declared bytes are read."""
    path = write_gltf(tmp_path / "big.gltf", **GOOD)
    doc = json.loads(path.read_text())
    uri = doc["buffers"][0]["uri"]
    blob = base64.b64decode(uri.partition(",")[2])
    with open(tmp_path / "big.bin", "wb") as f:
        f.write(blob)
        f.truncate(8 << 30)
    doc["buffers"][0]["uri"] = "big.bin"
    path.write_text(json.dumps(doc))
    tracemalloc.start()
    try:
        mesh = meshes.load_mesh(path)
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert len(mesh.vertices) == 6 and peak < 32 << 20, peak
    (tmp_path / "big.bin").write_bytes(blob)
    doc["buffers"][0]["byteLength"] = len(blob) + 4
    path.write_text(json.dumps(doc))
    refused(path, f"buffers[0]: {len(blob)} bytes, fewer than its byteLength {len(blob) + 4}", "truncated")


def _glb(json_chunk: bytes, chunks=b"", length=None) -> bytes:
    body = struct.pack("<I", len(json_chunk)) + b"JSON" + json_chunk + chunks
    return b"glTF" + struct.pack("<II", 2, length if length is not None else 12 + len(body)) + body


@pytest.mark.parametrize("data, parts", [
    (_glb(b"{}  ", struct.pack("<I", 0xFFFFFFF0) + b"BIN\0"), ["truncated: a chunk runs past the end"]),
    (_glb(b"{}  ", b"\1\0"), ["truncated: a chunk header runs past the end"]),
    (_glb(b"{}  ", length=1 << 31), ["truncated: its header says 2147483648 bytes"]),
    (b"glTF" + struct.pack("<II", 2, 24) + struct.pack("<I", 4) + b"BIN\0" + b"\0" * 4, ["GLB without a JSON chunk"]),
    (b"glTF" + struct.pack("<II", 1, 20) + b"\0" * 8, ["GLB version 1; expected 2"]),
    (_glb(b"[1, 2]"), ["its JSON is no object"]),
    (_glb(b'{"asset": {"version": "1.0"}}'), ["glTF version 1.0; expected 2.0"]),
    (_glb(b"[" * 100000), ["its JSON does not parse"]),
])
def test_hostile_glb_framing_is_refused(tmp_path, data, parts):
    path = tmp_path / "h.glb"
    path.write_bytes(data)
    refused(path, *parts)


def test_embedded_images_are_read_from_memory_without_a_temporary_folder(tmp_path):
    before = {p.name for p in Path(tempfile.gettempdir()).glob("wgpuviewer-mesh-images-*")}
    mesh = meshes.load_mesh(write_glb(tmp_path / "panel.glb"))
    source = mesh.material.albedo.path
    assert isinstance(source, ImageBytes) and str(source) == f"{tmp_path / 'panel.glb'}: images[0]"
    assert np.array_equal(np.round(read_image(source) * 255).astype(np.uint8), RED_BLUE)
    assert {p.name for p in Path(tempfile.gettempdir()).glob("wgpuviewer-mesh-images-*")} == before


def test_a_hostile_file_reaches_the_scene_as_one_line_naming_the_key(tmp_path):
    hostile(tmp_path, setter("bufferViews", 0, "byteStride", -1048576))
    scene = mesh_scene(tmp_path, "h.gltf")
    with pytest.raises(UserError) as error:
        load_scene(scene)
    assert str(error.value).startswith(f"{scene}: objects[0].file = 'h.gltf': bufferViews[0].byteStride = -1048576")


def test_the_strided_reader_checks_its_bounds_itself():
    raw = memoryview(bytes(64))
    assert gltf_accessors._rows(raw, 4, 5, 12, 12).shape == (5, 12)
    for offset, count, item, stride in ((-1, 1, 4, 4), (0, 2, 12, 8), (0, 6, 12, 12), (60, 1, 8, 8)):
        with pytest.raises(ValueError, match="bounds not checked"):
            gltf_accessors._rows(raw, offset, count, item, stride)


def with_transform(albedo: dict | None, normal: dict | None = None, required: bool = False):
    """A change giving the quad's material KHR_texture_transforms (None: none) on its albedo and a normal map."""
    def change(doc):
        material = doc["materials"][0]
        if albedo is not None:
            material["pbrMetallicRoughness"]["baseColorTexture"]["extensions"] = {"KHR_texture_transform": albedo}
        material["normalTexture"] = {"index": 0}
        if normal is not None:
            material["normalTexture"]["extensions"] = {"KHR_texture_transform": normal}
        doc["extensionsUsed"] = ["KHR_texture_transform"]
        if required:
            doc["extensionsRequired"] = ["KHR_texture_transform"]
    return change


@pytest.mark.parametrize("required", [False, True])
def test_a_texture_transform_is_applied_to_the_uvs(tmp_path, required):
    """offset, rotation and scale as the ratified extension defines them: uv' = T R S uv, R = [[c, s], [-s, c]]. Its
    own example (offset [0, 1], a quarter turn, scale 0.5) maps the uv square onto the image's lower-left quarter."""
    (tmp_path / "albedo.png").write_bytes(cv2.imencode(".png", RED_BLUE)[1].tobytes())
    transform = {"offset": [0, 1], "rotation": np.pi / 2, "scale": [0.5, 0.5]}
    path = hostile(tmp_path, with_transform(transform, transform, required), image_uri="albedo.png")
    uv = meshes.load_mesh(path).vertices[:, 10:12].astype(np.float64)
    corners = np.asarray(GOOD["positions"])[np.asarray(GOOD["faces"]).ravel()]
    original = QUAD_UV[np.asarray(GOOD["faces"]).ravel()]
    expected = np.stack([0.5 * original[:, 1], 1.0 - 0.5 * original[:, 0]], axis=1)
    assert np.allclose(meshes.load_mesh(path).vertices[:, :3], corners)
    assert np.allclose(uv, expected, atol=1e-6), uv
    assert uv[:, 0].max() <= 0.5 + 1e-6 and uv[:, 1].min() >= 0.5 - 1e-6  # the lower-left quarter


def test_textures_with_different_transforms_are_refused_by_name(tmp_path):
    (tmp_path / "albedo.png").write_bytes(cv2.imencode(".png", RED_BLUE)[1].tobytes())
    path = hostile(tmp_path, with_transform({"scale": [2, 2]}), image_uri="albedo.png")
    refused(path, "baseColorTexture and normalTexture have different KHR_texture_transforms")


def test_a_material_the_scene_replaces_is_not_read(tmp_path):
    """A damaged embedded image in the file's material: no error when the scene gives the object its own."""
    broken = "data:image/png;base64,iVBORw0KGgo="
    hostile(tmp_path, setter("images", 0, "uri", broken), image_uri="albedo.png")
    scene = load_scene(mesh_scene(tmp_path, "h.gltf", material="bricks"))
    assert scene.objects[0].material == "bricks" and scene.objects[0].size == (2.0, 2.0, 0.0)
    with pytest.raises(UserError, match="damaged or truncated PNG"):
        load_scene(mesh_scene(tmp_path, "h.gltf"))


def test_a_node_of_scale_0_is_left_out_with_a_warning(tmp_path, caplog):
    path = write_gltf(tmp_path / "two.gltf", **GOOD, nodes=[("shown", (0, 0, 0)), ("hidden", (3, 0, 0))])
    doc = json.loads(path.read_text())
    doc["nodes"][1]["scale"] = [0, 1, 1]
    path.write_text(json.dumps(doc))
    with caplog.at_level(logging.WARNING, "wgpuviewer.meshes"):
        mesh = meshes.load_mesh(path)
    assert len(mesh.vertices) == 6 and np.abs(mesh.vertices[:, 0]).max() == 1.0
    assert "node 'hidden' mesh 0 primitive 0: its node transform is flat (a scale of 0" in caplog.text
    doc["nodes"][0]["scale"] = [1, 0, 1]
    path.write_text(json.dumps(doc))
    refused(path, "mesh 0 primitive 0: its node transform is flat", "(and 1 more)", "nothing left to show")


@pytest.mark.parametrize("translation, parts", [
    ([1e20, 0, 0], ["places it 1e+20 from the origin, too far for float32"]),
    ([1e39, 0, 0], ["places it 1e+39 from the origin, beyond float32's range"]),
])
def test_triangles_lost_to_float32_name_the_node_transform(tmp_path, translation, parts):
    message = refused(hostile(tmp_path, setter("nodes", 0, "translation", translation)), "node 'quad'", *parts)
    assert "zero area" not in message


def test_an_image_behind_a_symbolic_link_loop_is_one_line(tmp_path):
    os.symlink(tmp_path / "b.png", tmp_path / "a.png")
    os.symlink(tmp_path / "a.png", tmp_path / "b.png")
    refused(hostile(tmp_path, lambda doc: None, image_uri="a.png"), "images[0]", "symbolic link loop")
