"""The one struct generator: a record's fields in Python -> its WGSL struct, its numpy dtype and its packer.

Every uniform and storage record that Python and WGSL share is declared once as a ``Struct`` and generated into
the module (``Struct.generated`` for ``core.wgsl.compose``), so the two sides cannot disagree on a type or an
offset. Layout follows WGSL's alignment and size rules (https://www.w3.org/TR/WGSL/#alignment-and-size): scalars
4/4, vec2 8/8, vec3 align 16 size 12 (a scalar may follow in the same 16 bytes), vec4 16/16, mat4x4f 16/64; a
struct's alignment is its largest member's and its size is rounded up to it; an array's stride is its element's
size rounded up to the element's alignment. The uniform address space adds rules (array strides, and the offsets
of array and struct members, multiples of 16; here struct members must also align to 16): a struct declared
"uniform" that breaks them is refused with the field named, never padded silently.

In the numpy dtype a vector is a float/int subarray, a ``mat4x4f`` is 4 columns of 4, and an array of a vec3 type
is (count, 4) (its stride) of which the first three are the vector.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import cached_property
from typing import Union

import numpy as np

from .wgsl import Generated

# WGSL type -> (alignment, size, numpy scalar type, numpy shape)
_BUILTINS: dict[str, tuple[int, int, str, tuple[int, ...]]] = {
    "f32": (4, 4, "<f4", ()), "u32": (4, 4, "<u4", ()), "i32": (4, 4, "<i4", ()),
    "vec2f": (8, 8, "<f4", (2,)), "vec2u": (8, 8, "<u4", (2,)), "vec2i": (8, 8, "<i4", (2,)),
    "vec3f": (16, 12, "<f4", (3,)), "vec3u": (16, 12, "<u4", (3,)), "vec3i": (16, 12, "<i4", (3,)),
    "vec4f": (16, 16, "<f4", (4,)), "vec4u": (16, 16, "<u4", (4,)), "vec4i": (16, 16, "<i4", (4,)),
    "mat4x4f": (16, 64, "<f4", (4, 4)),
}
ADDRESS_SPACES = ("uniform", "storage")


def _round_up(align: int, size: int) -> int:
    return -(-size // align) * align


@dataclass(frozen=True)
class ArrayType:
    """``array<element, count>``: a fixed-size array field."""

    element: FieldType
    count: int

    def __post_init__(self):
        _check_type(self.element)
        if self.count < 1:
            raise ValueError(f"array<{type_name(self.element)}, {self.count}>: the count must be at least 1")

    @property
    def align(self) -> int:
        return align_of(self.element)

    @property
    def stride(self) -> int:
        return _round_up(align_of(self.element), size_of(self.element))

    @property
    def size(self) -> int:
        return self.stride * self.count


def array(element: FieldType, count: int) -> ArrayType:
    """A fixed-size array field type: ``array(\"vec3f\", 4)`` is ``array<vec3f, 4>``."""
    return ArrayType(element, count)


FieldType = Union[str, "Struct", ArrayType]


def _check_type(t) -> None:
    if isinstance(t, str) and t not in _BUILTINS:
        raise ValueError(f"unknown WGSL type {t!r} (known: {', '.join(_BUILTINS)}, a Struct or array(...))")
    if not isinstance(t, (str, Struct, ArrayType)):
        raise TypeError(f"a field type is a WGSL type name, a Struct or array(...), not {t!r}")


def align_of(t: FieldType) -> int:
    return _BUILTINS[t][0] if isinstance(t, str) else t.align


def size_of(t: FieldType) -> int:
    return _BUILTINS[t][1] if isinstance(t, str) else t.size


def type_name(t: FieldType) -> str:
    if isinstance(t, str):
        return t
    if isinstance(t, Struct):
        return t.name
    return f"array<{type_name(t.element)}, {t.count}>"


def _dtype(t: FieldType) -> np.dtype:
    if isinstance(t, str):
        _, _, base, shape = _BUILTINS[t]
        return np.dtype((base, shape)) if shape else np.dtype(base)
    if isinstance(t, Struct):
        return t.dtype
    element = _dtype(t.element)
    if element.itemsize != t.stride:  # a vec3 element: padded to its stride of 16 bytes
        element = np.dtype((element.base, (t.stride // element.base.itemsize,)))
    return np.dtype((element, (t.count,)))


class Struct:
    """A WGSL struct generated from Python: ``Struct("Light", [("position", "vec3f"), ("radius", "f32")])``."""

    def __init__(self, name: str, fields: Sequence[tuple[str, FieldType]], address_space: str = "uniform",
                 defaults: Mapping[str, object] | None = None):
        if address_space not in ADDRESS_SPACES:
            raise ValueError(f"struct {name}: address space {address_space!r} is not one of {ADDRESS_SPACES}")
        if not fields:
            raise ValueError(f"struct {name}: a WGSL struct needs at least one field")
        self.name = name
        self.fields: tuple[tuple[str, FieldType], ...] = tuple(fields)
        self.address_space = address_space
        #: Values ``pack`` takes for fields it is given none for (e.g. padding); every other field is required.
        self.defaults = dict(defaults or {})
        names = [n for n, _ in self.fields]
        for n in names:
            if names.count(n) > 1:
                raise ValueError(f"struct {name}: field {n!r} appears twice")
        for n in self.defaults:
            if n not in names:
                raise ValueError(f"struct {name}: a default for {n!r}, which is not a field")
        offsets: dict[str, int] = {}
        offset = 0
        for n, t in self.fields:
            _check_type(t)
            offset = _round_up(align_of(t), offset)
            offsets[n] = offset
            offset += size_of(t)
        self.offsets = offsets
        self.align = max(align_of(t) for _, t in self.fields)
        self.size = _round_up(self.align, offset)
        if address_space == "uniform":
            self._check_uniform()

    def _check_uniform(self) -> None:
        """WGSL's uniform address space layout constraints, for this struct and every struct inside it (a struct
        member aligned to 16 also leaves the 16-rounded room after it that WGSL asks for: its size is a multiple
        of its alignment)."""
        for n, t in self.fields:
            where = f"uniform struct {self.name}: field {n!r} ({type_name(t)})"
            element = t
            while isinstance(element, ArrayType):
                if element.stride % 16:
                    raise ValueError(f"{where}: array stride {element.stride} is not a multiple of 16, which a "
                                     f"uniform needs (use a vec4 element or storage)")
                element = element.element
            if isinstance(t, ArrayType) and self.offsets[n] % 16:
                raise ValueError(f"{where} sits at offset {self.offsets[n]}; an array in a uniform needs a multiple "
                                 f"of 16 (add a field before it or use storage)")
            if isinstance(element, Struct):
                if self.offsets[n] % 16 or element.align % 16:
                    raise ValueError(f"{where}: a struct member of a uniform needs an alignment (and offset) that "
                                     f"is a multiple of 16; {element.name} aligns to {element.align} and sits at "
                                     f"offset {self.offsets[n]} (add a vec4-aligned field or use storage)")
                element._check_uniform()

    def __repr__(self) -> str:
        return f"Struct({self.name!r}, size={self.size}, align={self.align})"

    @property
    def names(self) -> tuple[str, ...]:
        return tuple(n for n, _ in self.fields)

    @cached_property
    def dtype(self) -> np.dtype:
        """A numpy structured dtype with WGSL's offsets; its itemsize is the struct's size (= its array stride)."""
        return np.dtype({"names": list(self.names), "formats": [_dtype(t) for _, t in self.fields],
                         "offsets": [self.offsets[n] for n in self.names], "itemsize": self.size})

    def dependencies(self) -> list[Struct]:
        """Every struct this one contains, each once, each after those it contains (not this one)."""
        order: list[Struct] = []

        def visit(t: FieldType) -> None:
            while isinstance(t, ArrayType):
                t = t.element
            if isinstance(t, Struct):
                for _, inner in t.fields:
                    visit(inner)
                if all(s is not t for s in order):
                    order.append(t)

        for _, t in self.fields:
            visit(t)
        return order

    def wgsl(self) -> str:
        """This struct's WGSL declaration (the structs it contains are not included: ``wgsl_all``)."""
        lines = [f"struct {self.name} {{", *(f"    {n}: {type_name(t)}," for n, t in self.fields), "}"]
        return "\n".join(lines) + "\n"

    def wgsl_all(self) -> str:
        """The declarations of every struct this one contains, then this one's."""
        return "".join(s.wgsl() for s in (*self.dependencies(), self))

    def generated(self, extra: str = "") -> Generated:
        """``wgsl_all`` (and ``extra`` WGSL after it) as a piece for ``core.wgsl.compose``."""
        return Generated(f"<generated: struct {self.name}>", self.wgsl_all() + extra)

    def _fill(self, record: np.void | np.ndarray, values: Mapping) -> None:
        unknown = [n for n in values if n not in self.offsets]
        if unknown:
            raise ValueError(f"struct {self.name} has no field {unknown[0]!r} (fields: {', '.join(self.names)})")
        missing = [n for n in self.names if n not in values and n not in self.defaults]
        if missing:
            raise ValueError(f"struct {self.name}: no value for field {missing[0]!r}")
        for n, t in self.fields:
            value = values[n] if n in values else self.defaults[n]
            if isinstance(t, Struct):
                t._fill(record[n], value)
            elif isinstance(t, ArrayType) and isinstance(t.element, Struct):
                if len(value) != t.count:
                    raise ValueError(f"struct {self.name}: field {n!r} takes {t.count} records, not {len(value)}")
                if isinstance(value, np.ndarray):  # records already in the element's layout: one copy, no loop
                    if value.dtype != t.element.dtype:
                        raise ValueError(f"struct {self.name}: field {n!r} takes {t.element.name} records, "
                                         f"not dtype {value.dtype}")
                    record[n] = value
                    continue
                for i, item in enumerate(value):
                    t.element._fill(record[n][..., i], item)
            elif isinstance(t, ArrayType) and _dtype(t).base.shape != _dtype(t.element).shape:
                record[n][..., :_dtype(t.element).shape[0]] = value  # vec3 elements: the 4th word is padding
            else:
                record[n] = value

    def pack(self, values: Mapping) -> bytes:
        """One record's bytes (``size`` of them): a value for every field, by name (nested structs as mappings)."""
        return self.pack_many([values])

    def pack_many(self, records: Sequence[Mapping] | np.ndarray) -> bytes:
        """Records back to back (stride ``size``): mappings, or a numpy structured array of this ``dtype``."""
        if isinstance(records, np.ndarray):
            if records.dtype != self.dtype:
                raise ValueError(f"struct {self.name}: records of dtype {records.dtype} are not of its dtype")
            return np.ascontiguousarray(records).tobytes()
        data = np.zeros(len(records), self.dtype)
        for i, values in enumerate(records):
            self._fill(data[i : i + 1], values)
        return data.tobytes()

    def unpack(self, data: bytes | memoryview, count: int | None = None) -> np.ndarray:
        """Records from ``data`` (all whole records in it, or the first ``count``) as a structured array."""
        buffer = memoryview(data).cast("B")
        available = len(buffer) // self.size
        count = available if count is None else count
        if count > available:
            raise ValueError(f"struct {self.name}: {len(buffer)} bytes hold {available} records, not {count}")
        return np.frombuffer(buffer[: count * self.size], self.dtype).copy()


#: The scalar types of ``scalar_uniform`` fields (and of ``scalar_literal``).
SCALARS = ("f32", "u32", "i32")


def scalar_uniform(name: str, fields: Sequence[tuple[str, str]], pad_to: int = 16) -> Struct:
    """A uniform of scalar ``fields`` ((name, "f32" | "u32" | "i32") pairs; at least one: ``_unused``), padded with
    zeroed u32 ``_padN`` fields to a multiple of ``pad_to`` bytes (the technique and filter parameter records)."""
    fields = list(fields)
    for n, t in fields:
        if not (isinstance(t, str) and t in SCALARS):
            raise ValueError(f"struct {name}: field {n!r} is {t!r}; a scalar uniform takes {', '.join(SCALARS)}")
    unused = [] if fields else [("_unused", "u32")]
    pads = [(f"_pad{i}", "u32") for i in range(-len(fields + unused) % (pad_to // 4))]
    return Struct(name, fields + unused + pads, "uniform", defaults={n: 0 for n, _ in unused + pads})


def f32_literal(x: float) -> str:
    """``x`` as a WGSL f32 literal (always with a '.' or an exponent, so WGSL does not read an integer)."""
    text = repr(float(x))
    return text if "e" in text or "." in text else text + ".0"


def scalar_literal(value, wgsl_type: str) -> str:
    """``value`` as a WGSL literal of scalar type ``wgsl_type``: an f32 literal, or an integer with its ``u``/``i``
    suffix (a value that is not an integer, or a negative u32, is refused)."""
    if wgsl_type == "f32":
        return f32_literal(value)
    if wgsl_type not in SCALARS:
        raise ValueError(f"{wgsl_type!r} is not a scalar type ({', '.join(SCALARS)})")
    if isinstance(value, bool) or not float(value).is_integer() or (wgsl_type == "u32" and value < 0):
        raise ValueError(f"{value!r} is not a {wgsl_type} value")
    return f"{int(value)}{wgsl_type[0]}"


def range_constants(params) -> list[str]:
    """``const NAME_MIN: T = ...;`` and ``NAME_MAX`` in the parameter's own type T for every non-boolean parameter
    (the registries' ``Param``: ``name``, ``kind``, ``min``, ``max``, ``wgsl_type``), the bounds WGSL clamps a
    parameter to."""
    lines = []
    for p in params:
        if p.kind is not bool:
            lines += [f"const {p.name.upper()}_MIN: {p.wgsl_type} = {scalar_literal(p.min, p.wgsl_type)};",
                      f"const {p.name.upper()}_MAX: {p.wgsl_type} = {scalar_literal(p.max, p.wgsl_type)};"]
    return lines


# Colour format name prefix -> its channels (WebGPU's renderable colour formats; depth formats have none).
_FORMAT_CHANNELS = (("rgba", 4), ("bgra", 4), ("rgb10a2", 4), ("rg11b10", 3), ("rg", 2), ("r", 1))
_OUTPUT_SCALARS = {"<f4": "f32", "<u4": "u32", "<i4": "i32"}


class FragmentOutputs:
    """A fragment entry point's output struct, generated from its render targets in order (location = position):
    ``FragmentOutputs("Out", [("color", "vec4f", "rgba8unorm"), ("count", "u32", "r32uint")])`` declares
    ``struct Out { @location(0) color: vec4f, @location(1) count: u32, }`` and its ``formats`` are the pipeline's
    target formats, so what the shader writes and the textures it writes to come from one list. An output's type
    must have its format's sample type (u32 for uint formats, i32 for sint, f32 for the others) and at least its
    channels, as WebGPU asks of a pipeline: a mismatch is refused here, naming the output."""

    def __init__(self, name: str, targets: Sequence[tuple[str, str, str]]):
        if not targets:
            raise ValueError(f"fragment outputs {name}: at least one target")
        for field, wgsl_type, fmt in targets:
            where = f"fragment outputs {name}: {field!r} ({wgsl_type}) to {fmt}"
            channels = next((n for prefix, n in _FORMAT_CHANNELS if fmt.startswith(prefix)), None)
            if channels is None:
                raise ValueError(f"{where}: {fmt!r} is not a colour format")
            if wgsl_type not in _BUILTINS or len(_BUILTINS[wgsl_type][3]) > 1:
                raise ValueError(f"{where}: an output is a scalar or vector of f32, u32 or i32")
            _, _, base, shape = _BUILTINS[wgsl_type]
            scalar = "u32" if fmt.endswith("uint") else "i32" if fmt.endswith("sint") else "f32"
            if _OUTPUT_SCALARS[base] != scalar or (shape[0] if shape else 1) < channels:
                raise ValueError(f"{where}: the format needs {scalar} with at least {channels} components")
        self.name = name
        self.targets: tuple[tuple[str, str, str], ...] = tuple(targets)

    @property
    def formats(self) -> tuple[str, ...]:
        return tuple(fmt for _, _, fmt in self.targets)

    def wgsl(self) -> str:
        lines = [f"struct {self.name} {{",
                 *(f"    @location({i}) {field}: {t}," for i, (field, t, _) in enumerate(self.targets)), "}"]
        return "\n".join(lines) + "\n"

    def generated(self) -> Generated:
        """``wgsl`` as a piece for ``core.wgsl.compose``."""
        return Generated(f"<generated: struct {self.name}>", self.wgsl())
