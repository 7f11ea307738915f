"""The struct generator against WGSL's layout rules (hand-computed layouts), its packer, and naga/the GPU itself:
a kernel writes known values field by field into a storage buffer of a generated struct and ``unpack`` reads
them back where the generator says they are."""

from __future__ import annotations

import numpy as np
import pytest

from wgpuviewer.core.compute import compute_for
from wgpuviewer.core.structs import Struct, array, f32_literal, range_constants, scalar_literal, scalar_uniform
from wgpuviewer.core.wgsl import compose

LIGHT = Struct("Light", [("position", "vec3f"), ("radius", "f32"), ("color", "vec3f")])
RECORD = Struct("Record", [
    ("a", "f32"),  # 0
    ("v", "vec3f"),  # 16: align 16
    ("w", "f32"),  # 28: in the vec3's 16 bytes
    ("n", "u32"),  # 32
    ("uv", "vec2f"),  # 40: align 8
    ("k", "i32"),  # 48
    ("points", array("vec3f", 3)),  # 64: stride 16
    ("light", LIGHT),  # 112: align 16, size 32
    ("lights", array(LIGHT, 2)),  # 144: stride 32
    ("m", "mat4x4f"),  # 208
], address_space="storage")


def test_hand_computed_layout():
    assert RECORD.offsets == {"a": 0, "v": 16, "w": 28, "n": 32, "uv": 40, "k": 48, "points": 64, "light": 112,
                              "lights": 144, "m": 208}
    assert (RECORD.size, RECORD.align) == (272, 16)
    assert (LIGHT.offsets, LIGHT.size, LIGHT.align) == ({"position": 0, "radius": 12, "color": 16}, 32, 16)
    assert RECORD.dtype.itemsize == RECORD.size and RECORD.dtype.fields["m"][1] == 208


def test_vec3_and_f32_share_16_bytes_and_size_rounds_to_alignment():
    s = Struct("S", [("v", "vec3f"), ("f", "f32")])
    assert (s.offsets, s.size) == ({"v": 0, "f": 12}, 16)
    t = Struct("T", [("f", "f32"), ("v", "vec3f")])
    assert (t.offsets, t.size) == ({"f": 0, "v": 16}, 32)
    u = Struct("U", [("a", "f32"), ("b", "u32"), ("c", "i32")])
    assert (u.size, u.align) == (12, 4)


def test_array_strides():
    assert array("vec3f", 5).stride == 16 and array("vec3f", 5).size == 80
    assert array("f32", 3).stride == 4 and array("vec2u", 2).stride == 8
    assert array(LIGHT, 2).stride == 32 and array(Struct("P", [("v", "vec3f")], "storage"), 2).stride == 16


def test_wgsl_text_with_dependencies_first():
    assert LIGHT.wgsl() == "struct Light {\n    position: vec3f,\n    radius: f32,\n    color: vec3f,\n}\n"
    text = RECORD.wgsl_all()
    assert text.index("struct Light {") < text.index("struct Record {") and text.count("struct Light {") == 1
    assert "    points: array<vec3f, 3>,\n" in text and "    lights: array<Light, 2>,\n" in text
    assert RECORD.generated().name == "<generated: struct Record>"


@pytest.mark.parametrize("fields, words", [
    ([("a", "f32"), ("xs", array("f32", 4))], "array stride 4"),
    ([("a", "vec4f"), ("xs", array("vec2f", 2))], "array stride 8"),
    ([("a", "f32"), ("s", Struct("Small", [("x", "f32")], "storage"))], "multiple of 16"),
    ([("a", "f32"), ("ps", array(Struct("Four", [("x", "vec2f"), ("y", "vec2f")], "storage"), 2))], "offset 8"),
])
def test_uniform_rules_are_refused_not_padded(fields, words):
    with pytest.raises(ValueError, match=words):
        Struct("Bad", fields, "uniform")
    Struct("Fine", fields, "storage")


def test_unknown_types_fields_and_spaces_are_refused():
    with pytest.raises(ValueError, match="unknown WGSL type 'vec5f'"):
        Struct("S", [("a", "vec5f")])
    with pytest.raises(ValueError, match="address space"):
        Struct("S", [("a", "f32")], "private")
    with pytest.raises(ValueError, match="twice"):
        Struct("S", [("a", "f32"), ("a", "u32")])
    with pytest.raises(ValueError, match="struct Light has no field 'radiuss'"):
        LIGHT.pack({"position": (1, 2, 3), "radiuss": 1, "color": (0, 0, 0)})
    with pytest.raises(ValueError, match="struct Light: no value for field 'color'"):
        LIGHT.pack({"position": (1, 2, 3), "radius": 1})


def record_values(scale: float = 1.0) -> dict:
    light = {"position": np.array([1, 2, 3]) * scale, "radius": 4 * scale, "color": np.array([5, 6, 7]) * scale}
    return {"a": 1.5 * scale, "v": np.array([2, 3, 4]) * scale, "w": 5 * scale, "n": 4000000000, "uv": (6, 7),
            "k": -9, "points": np.arange(9).reshape(3, 3) * scale, "light": light, "lights": [light, light],
            "m": np.arange(16).reshape(4, 4) * scale}


def check_record(got: np.void, values: dict) -> None:
    for name in ("a", "v", "w", "n", "uv", "k", "m"):
        assert np.array_equal(got[name], np.asarray(values[name], got[name].dtype)), name
    assert np.array_equal(got["points"][:, :3], values["points"])
    for light in (got["light"], *got["lights"]):
        for name in ("position", "radius", "color"):
            assert np.allclose(light[name], values["light"][name]), name


def test_pack_unpack_round_trip():
    data = RECORD.pack_many([record_values(1.0), record_values(2.0)])
    assert len(data) == 2 * RECORD.size
    got = RECORD.unpack(data)
    check_record(got[0], record_values(1.0))
    check_record(got[1], record_values(2.0))
    assert RECORD.pack_many(got) == data and len(RECORD.unpack(data, 1)) == 1
    offsets = np.frombuffer(data, np.float32)
    assert offsets[7] == 5.0 and np.frombuffer(data, np.int32)[12] == -9  # w at byte 28, k at byte 48
    with pytest.raises(ValueError, match="hold 2 records, not 3"):
        RECORD.unpack(data, 3)


def test_an_array_of_structs_takes_records_of_the_element_dtype_as_is():
    light = Struct("L", [("vector", "vec4f"), ("color", "vec4f")])
    frame = Struct("F", [("count", "u32"), ("lights", array(light, 3))])
    records = np.zeros(3, light.dtype)
    records["color"][1] = [1, 2, 3, 0]
    as_array = frame.pack({"count": 2, "lights": records})
    as_mappings = frame.pack({"count": 2, "lights": [{"vector": r["vector"], "color": r["color"]} for r in records]})
    assert as_array == as_mappings
    assert frame.unpack(as_array)["lights"][0, 1]["color"].tolist() == [1, 2, 3, 0]
    other = Struct("M", [("vector", "vec4f"), ("color", "vec4i")])
    with pytest.raises(ValueError, match="takes L records"):
        frame.pack({"count": 2, "lights": np.zeros(3, other.dtype)})

def test_defaults_and_padded_scalar_uniforms():
    params = scalar_uniform("Params", [("a", "f32"), ("n", "u32"), ("k", "i32"), ("flag", "u32"), ("e", "f32")])
    assert params.names == ("a", "n", "k", "flag", "e", "_pad0", "_pad1", "_pad2") and params.size == 32
    assert params.wgsl() == ("struct Params {\n    a: f32,\n    n: u32,\n    k: i32,\n    flag: u32,\n    e: f32,\n"
                             "    _pad0: u32,\n    _pad1: u32,\n    _pad2: u32,\n}\n")
    data = params.pack(dict(a=0.5, n=16, k=-2, flag=True, e=3))
    # each value in its field's own type, not a float's bits
    assert np.frombuffer(data, np.uint32)[[1, 3, 5, 6, 7]].tolist() == [16, 1, 0, 0, 0]
    assert np.frombuffer(data, np.int32)[2] == -2
    assert np.frombuffer(data, np.float32)[[0, 4]].tolist() == [0.5, 3.0]
    assert scalar_uniform("Empty", []).names == ("_unused", "_pad0", "_pad1", "_pad2")
    assert scalar_uniform("Empty", []).pack({}) == bytes(16)
    with pytest.raises(ValueError, match="no value for field 'e'"):
        params.pack(dict(a=1, n=2, k=3, flag=0))
    with pytest.raises(ValueError, match="field 'v' is 'vec2f'; a scalar uniform takes f32, u32, i32"):
        scalar_uniform("S", [("v", "vec2f")])
    with pytest.raises(ValueError, match="not a field"):
        Struct("S", [("a", "f32")], defaults={"b": 0})


def test_constants():
    assert f32_literal(2) == "2.0" and f32_literal(0.25) == "0.25" and f32_literal(1e-7) == "1e-07"

    assert scalar_literal(3, "u32") == "3u" and scalar_literal(-8, "i32") == "-8i" and scalar_literal(2, "f32") == "2.0"
    for value, wgsl_type in ((-1, "u32"), (2.5, "i32"), (True, "u32")):
        with pytest.raises(ValueError, match=f"is not a {wgsl_type} value"):
            scalar_literal(value, wgsl_type)
    with pytest.raises(ValueError, match="not a scalar type"):
        scalar_literal(1, "vec2u")

    class P:
        def __init__(self, name, kind, lo, hi, wgsl_type):
            self.name, self.kind, self.min, self.max, self.wgsl_type = name, kind, lo, hi, wgsl_type

    # the bounds in the parameter's own type, so WGSL clamps it without a conversion; none for a flag
    assert range_constants([P("layers", int, 4, 64, "u32"), P("offset", int, -8, 8, "i32"), P("alpha", float, 1.6, 8, "f32"),
                            P("flag", bool, 0, 1, "u32")]) == [
        "const LAYERS_MIN: u32 = 4u;", "const LAYERS_MAX: u32 = 64u;", "const OFFSET_MIN: i32 = -8i;",
        "const OFFSET_MAX: i32 = 8i;", "const ALPHA_MIN: f32 = 1.6;", "const ALPHA_MAX: f32 = 8.0;"]


WRITE = """@group(0) @binding(0) var<storage, read_write> out: array<Record>;

fn light(s: f32) -> Light {
    return Light(vec3f(1.0, 2.0, 3.0) * s, 4.0 * s, vec3f(5.0, 6.0, 7.0) * s);
}

@compute @workgroup_size(1)
fn main() {
    for (var i = 0u; i < 2u; i++) {
        let s = f32(i + 1u);
        out[i].a = 1.5 * s;
        out[i].v = vec3f(2.0, 3.0, 4.0) * s;
        out[i].w = 5.0 * s;
        out[i].n = 4000000000u;
        out[i].uv = vec2f(6.0, 7.0);
        out[i].k = -9;
        for (var p = 0u; p < 3u; p++) {
            out[i].points[p] = vec3f(f32(3u * p), f32(3u * p + 1u), f32(3u * p + 2u)) * s;
        }
        out[i].light = light(s);
        out[i].lights[0] = light(s);
        out[i].lights[1] = light(s);
        out[i].m = mat4x4f(0.0, 1.0, 2.0, 3.0, 4.0, 5.0, 6.0, 7.0, 8.0, 9.0, 10.0, 11.0, 12.0, 13.0, 14.0, 15.0) * s;
    }
}
"""


@pytest.mark.requires_gpu
def test_the_gpu_writes_fields_where_the_generator_puts_them(gpu, tmp_path):
    path = tmp_path / "write.wgsl"
    path.write_text(WRITE)
    assert "struct Record" in compose(RECORD.generated(), str(path)).code
    c = compute_for(gpu)
    kernel = c.kernel(RECORD.generated(), str(path), label="test structs", fix="a generator bug")
    with c.guard("test structs", "a generator bug"):
        out = c.storage(RECORD.pack_many([record_values(0.0)] * 2), "test records", "a generator bug")
        encoder = c.encoder("test structs")
        kernel.dispatch(encoder, "main", {0: out}, threads=(1,), size=(1,))
        c.submit(encoder)
        got = RECORD.unpack(c.read(out, 2 * RECORD.size // 4, np.uint32).tobytes())
    check_record(got[0], record_values(1.0))
    check_record(got[1], record_values(2.0))
