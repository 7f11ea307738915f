"""Fuzzing the mesh readers (wgpuviewer.meshes through scene loading): seeded random mutations of valid glTF, GLB and
OBJ files made here (bytes flipped, files cut, JSON values swapped for other types, huge, negative or non-finite
numbers, keys dropped, OBJ tokens and lines replaced) each end in a loaded mesh with finite vertices or a one-line
UserError, never another exception; a few of them go through the CLI in a subprocess, which must exit 2 (no signal,
no internal error). ``WGPUVIEWER_FUZZ_SEED`` picks other mutations (the default keeps runs repeatable)."""

from __future__ import annotations

import base64
import copy
import json
import os
import struct
import subprocess
import sys
import warnings
from pathlib import Path

import cv2
import numpy as np
import pytest

from tests.test_meshes import QUAD_FACES, QUAD_POSITIONS, QUAD_UV, RED_BLUE, mesh_scene, write_gltf, write_obj
from wgpuviewer import meshes
from wgpuviewer.core.errors import UserError
from wgpuviewer.scene import load_scene

SEED = int(os.environ.get("WGPUVIEWER_FUZZ_SEED", "3"))
#: Mutated files per kind and run.
CASES = {"gltf": 100, "glb": 80, "obj": 100}
#: Values a JSON mutation puts in place of another.
JSON_VALUES = [None, True, False, "", "x", "../../x.bin", "data:,", [], {}, [1] * 17, {"a": 1}, 0, 1, -1, 3, 7,
               -2**31, 2**31, 2**63, 10**30, 0.5, -0.0, 1e308, -1e308, 1e39, float("nan"), float("inf"), 5126, 5121]
#: Tokens an OBJ mutation puts in place of another.
OBJ_TOKENS = ["-1", "0", "2", "-99", "99999999", "1e39", "-1e39", "nan", "inf", "-2147483649", "1/", "//", "1//1",
              "x", "", "f", "v", "vt", "usemtl", "mtllib", "o"]


def base_gltf(folder: Path) -> dict:
    """A quad under a parent node with a matrix, with normals, a material with an embedded PNG albedo, a normal
    map and a texture transform: the JSON of a valid .gltf (its buffer a data URI)."""
    normals = np.tile([0.0, 0.0, 1.0], (4, 1))
    doc = json.loads(write_gltf(folder / "base.gltf", QUAD_POSITIONS, QUAD_UV, QUAD_FACES, normals).read_text())
    png = cv2.imencode(".png", RED_BLUE[:4, :4])[1].tobytes()
    doc["images"] = [{"uri": "data:image/png;base64," + base64.b64encode(png).decode()}]
    doc["textures"] = [{"source": 0}]
    transform = {"KHR_texture_transform": {"offset": [0.5, 0], "rotation": 0.3, "scale": [2, 1]}}
    doc["materials"] = [{"name": "m", "normalTexture": {"index": 0, "extensions": transform},
                         "pbrMetallicRoughness": {"baseColorTexture": {"index": 0, "extensions": transform},
                                                  "baseColorFactor": [1, 1, 1, 1]}}]
    doc["meshes"][0]["primitives"][0]["material"] = 0
    doc["nodes"].append({"name": "parent", "children": [0], "matrix": [1, 0, 0, 0, 0, 2, 0, 0, 0, 0, 1, 0, 1, 2, 3, 1]})
    doc["scenes"] = [{"nodes": [1]}]
    doc["extensionsUsed"] = ["KHR_texture_transform"]
    return doc


def glb_form(doc: dict) -> tuple[dict, bytes]:
    """(``doc`` with its data-URI buffer taken out, the buffer's bytes): the parts of a GLB."""
    doc = copy.deepcopy(doc)
    blob = base64.b64decode(doc["buffers"][0].pop("uri").partition(",")[2])
    blob += b"\0" * (-len(blob) % 4)
    doc["buffers"][0]["byteLength"] = len(blob)
    return doc, blob


def glb_bytes(doc: dict, blob: bytes) -> bytes:
    """A GLB of JSON ``doc`` and binary chunk ``blob``."""
    text = json.dumps(doc).encode()
    text += b" " * (-len(text) % 4)
    body = struct.pack("<I", len(text)) + b"JSON" + text + struct.pack("<I", len(blob)) + b"BIN\0" + blob
    return b"glTF" + struct.pack("<II", 2, 12 + len(body)) + body


def json_paths(value, path=()):
    """Every (path to a value) in a JSON document."""
    yield path
    items = value.items() if isinstance(value, dict) else enumerate(value) if isinstance(value, list) else ()
    for key, item in items:
        yield from json_paths(item, (*path, key))


def mutate_json(rng: np.random.Generator, doc: dict) -> dict:
    doc = copy.deepcopy(doc)
    for _ in range(rng.integers(1, 4)):
        paths = [p for p in json_paths(doc) if p]
        *parent_path, key = paths[rng.integers(len(paths))]
        parent = doc
        for k in parent_path:
            parent = parent[k]
        action = rng.integers(4)
        if action == 0 and isinstance(parent, dict):
            del parent[key]
        elif action == 1 and isinstance(parent, list):
            parent.append(copy.deepcopy(parent[key]))
        else:
            parent[key] = copy.deepcopy(JSON_VALUES[rng.integers(len(JSON_VALUES))])
    return doc


def mutate_bytes(rng: np.random.Generator, data: bytes) -> bytes:
    data = bytearray(data)
    action = rng.integers(3)
    if action == 0:  # flip bytes
        for at in rng.integers(0, len(data), rng.integers(1, 9)):
            data[at] ^= int(rng.integers(1, 256))
    elif action == 1:  # cut
        del data[rng.integers(0, len(data)):]
    else:  # a 32-bit field (a GLB length, a float, an index) set to an extreme
        at = int(rng.integers(0, max(1, len(data) - 4)))
        data[at:at + 4] = struct.pack("<I", int(rng.choice([0, 1, 0xFFFFFFFF, 0x7FFFFFFF, 0x80000000, 12])))
    return bytes(data)


def mutate_obj(rng: np.random.Generator, text: str) -> str:
    lines = text.splitlines()
    for _ in range(rng.integers(1, 4)):
        at = int(rng.integers(len(lines)))
        action = rng.integers(3)
        if action == 0:
            tokens = lines[at].split(" ")
            tokens[rng.integers(len(tokens))] = OBJ_TOKENS[rng.integers(len(OBJ_TOKENS))]
            lines[at] = " ".join(tokens)
        elif action == 1:
            del lines[at]
        else:
            lines.insert(int(rng.integers(len(lines) + 1)), lines[at])
    return "\n".join(lines) + "\n"


def mutant(rng: np.random.Generator, kind: str, folder: Path, index: int, bases: dict) -> Path:
    """Mutated file ``index`` of ``kind`` (an OBJ's .mtl mutated instead now and then), written into ``folder``."""
    name = f"m{index}.{kind}"
    if kind == "obj":
        text = bases["obj"]
        if rng.random() < 0.2:  # its material library instead
            (folder / f"m{index}.mtl").write_text(mutate_obj(rng, bases["mtl"]))
            text = text.replace("mtllib panel.mtl", f"mtllib m{index}.mtl")
        data = mutate_obj(rng, text).encode() if rng.random() < 0.8 else mutate_bytes(rng, text.encode())
    elif kind == "glb":
        doc, blob = bases["glb"]
        data = glb_bytes(mutate_json(rng, doc), blob) if rng.random() < 0.6 else mutate_bytes(rng, glb_bytes(doc, blob))
    else:
        doc = bases["gltf"]
        data = json.dumps(mutate_json(rng, doc)).encode() if rng.random() < 0.6 else mutate_bytes(rng, json.dumps(doc).encode())
    (folder / name).write_bytes(data)
    return folder / name


@pytest.fixture(scope="module")
def bases(tmp_path_factory) -> tuple[Path, dict]:
    folder = tmp_path_factory.mktemp("fuzz")
    write_obj(folder)
    gltf = base_gltf(folder)
    bases = {"gltf": gltf, "glb": glb_form(gltf), "obj": (folder / "panel.obj").read_text(),
             "mtl": (folder / "panel.mtl").read_text()}
    return folder, bases


def outcome(folder: Path, path: Path) -> str:
    """'ok' (the mesh loaded with finite float32 vertices) or 'refused' (a UserError); anything else raises, a
    numpy RuntimeWarning too (it would print lines of its own on the CLI's stderr)."""
    meshes.clear_cache()
    with warnings.catch_warnings():
        warnings.simplefilter("error", RuntimeWarning)
        try:
            scene = load_scene(mesh_scene(folder, path.name))
        except UserError as error:
            assert "\n" not in str(error), error
            return "refused"
        vertices = meshes.for_object(scene.objects[0])
    assert vertices.dtype == np.float32 and vertices.shape[1] == 12 and len(vertices) % 3 == 0
    assert len(vertices) and np.isfinite(vertices).all()
    return "ok"


@pytest.mark.parametrize("kind", CASES)
def test_mutated_files_load_or_are_refused_in_one_line(bases, kind):
    folder, files = bases
    rng = np.random.default_rng([SEED, list(CASES).index(kind)])
    seen, failures = {"ok": 0, "refused": 0}, []
    for index in range(CASES[kind]):
        path = mutant(rng, kind, folder, index, files)
        try:
            seen[outcome(folder, path)] += 1
        except Exception as error:  # noqa: BLE001 - the finding: collected with its file, all reported at once
            failures.append(f"{path.name}: {type(error).__name__}: {error}")
    assert not failures, f"seed {SEED}, {len(failures)} of {CASES[kind]}:\n" + "\n".join(failures[:10])
    assert seen["ok"] and seen["refused"], seen  # the mutations reach both outcomes


#: Runs ``wgpuviewer render`` (its ``main``, as the console script does) on each scene named in argv, printing
#: each exit status: one process for all, as starting the CLI is the slow part.
RENDER_EACH = """import sys
from wgpuviewer import cli
for scene in sys.argv[2:]:
    print(cli.main(["render", scene, "-o", sys.argv[1], "--size", "16x16"]), flush=True)
"""


def test_refused_mutants_exit_2_through_the_cli(bases, tmp_path):
    """One refused mutant of each kind through the CLI in a subprocess: exit 2 each, one error line each, no
    traceback, no signal."""
    folder, files = bases
    scenes = []
    for kind in CASES:
        rng = np.random.default_rng([SEED, 99, list(CASES).index(kind)])
        path = next(p for i in range(50) if outcome(folder, p := mutant(rng, kind, folder, 1000 + i, files)) == "refused")
        (tmp_path / kind).mkdir()
        scenes.append(str(mesh_scene(tmp_path / kind, str(path))))  # the mutant by its absolute path
    result = subprocess.run([sys.executable, "-c", RENDER_EACH, str(tmp_path / "x.png"), *scenes],
                            capture_output=True, text=True, timeout=120)
    errors = [line for line in result.stderr.splitlines() if line.startswith("wgpuviewer: error: ")]
    assert result.returncode == 0 and result.stdout.split() == ["2"] * len(scenes), result.stderr
    assert len(errors) == len(scenes) and "Traceback" not in result.stderr, result.stderr
