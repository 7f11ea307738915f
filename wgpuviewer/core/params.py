"""Parameters of registry entries (techniques, texture filters): a user parameter with its default and range
(``Param``), a value fixed by the entry with its WGSL type (``Fixed``), lookups and defaults for anything holding
parameters (``Parametrized``), and the checked merge of a user's overrides with the defaults (``resolve_params``).

May import: the standard library and ``wgpuviewer.core`` only.
"""

from __future__ import annotations

from dataclasses import dataclass

from wgpuviewer.core.errors import UserError


@dataclass(frozen=True)
class Param:
    name: str
    default: float
    min: float
    max: float
    kind: type  # int, float or bool
    doc: str

    def validate(self, value, where: str):
        """Checked value, or UserError naming ``where`` (e.g. 'scene.toml: techniques.pom.layers')."""
        expected = {int: "an integer", float: "a number", bool: "true or false"}[self.kind]
        ok_type = isinstance(value, bool) if self.kind is bool else (
            isinstance(value, int) and not isinstance(value, bool)
            if self.kind is int
            else isinstance(value, (int, float)) and not isinstance(value, bool)
        )
        if not ok_type:
            raise UserError(f"{where} = {value!r}: expected {expected}")
        if self.kind is not bool and not (self.min <= value <= self.max):
            raise UserError(f"{where} = {value!r}: out of range, expected {self.min:g} to {self.max:g}")
        return self.kind(value)

    @property
    def wgsl_type(self) -> str:
        """Its type in the generated uniform and its NAME_MIN / NAME_MAX constants: f32 for a number, u32 for a flag
        (0 or 1) and for an integer whose range starts at 0 or above, i32 for one whose range goes below 0."""
        if self.kind is float:
            return "f32"
        return "i32" if self.kind is int and self.min < 0 else "u32"


#: The WGSL types a fixed TraceParams value may have: a count, a signed integer, a real number.
FIXED_TYPES = ("u32", "i32", "f32")


@dataclass(frozen=True)
class Fixed:
    """A TraceParams value fixed by the technique (not a user parameter), e.g. a property of the map it samples,
    with its WGSL type: ``u32`` (a count), ``i32`` (a signed integer) or ``f32`` (a real number)."""

    name: str
    value: int | float
    wgsl_type: str

    def __post_init__(self):
        if self.wgsl_type not in FIXED_TYPES:
            raise ValueError(f"fixed value {self.name!r}: type {self.wgsl_type!r} is not one of {', '.join(FIXED_TYPES)}")
        integer = isinstance(self.value, int) and not isinstance(self.value, bool)
        if self.wgsl_type != "f32" and not (integer and (self.wgsl_type == "i32" or self.value >= 0)):
            raise ValueError(f"fixed value {self.name!r} = {self.value!r} is not a {self.wgsl_type}")


class Parametrized:
    """A registry entry with ``name`` and ``params`` (a tuple of Param): lookup by name and the default values."""

    def param(self, name: str) -> Param:
        for p in self.params:
            if p.name == name:
                return p
        raise KeyError(name)

    def defaults(self) -> dict:
        return {p.name: p.kind(p.default) for p in self.params}


def resolve_params(entry: Parametrized, overrides: dict | None = None, where: str = "", kind: str = "technique") -> dict:
    """Defaults merged with checked overrides (unknown names are errors naming ``where``), for any registry entry:
    a technique, or a texture filter (``kind="filter"``)."""
    values = entry.defaults()
    for name, value in (overrides or {}).items():
        key = f"{where}{name}" if where else f"{entry.name}.{name}"
        try:
            param = entry.param(name)
        except KeyError:
            known = ", ".join(p.name for p in entry.params) or "none"
            raise UserError(f"{key}: unknown parameter of {kind} {entry.name!r}; known: {known}") from None
        values[name] = param.validate(value, key)
    return values
