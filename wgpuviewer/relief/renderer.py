"""Drawing a scene with one technique, into a window surface or offscreen.

What to draw comes per draw as a frozen ``DrawConfig`` (technique, its parameters, a height-scale override, the
texture filter with its parameters and the derivative source it is given); the renderer holds no per-technique
state of its own beyond caches. Everything is built lazily from what the drawn technique needs ("model only what
a scene needs"): a material's depth texture exists only once a technique that traces depth is drawn, pipelines are
compiled on first use and cached per technique x filter x derivative source x material variant (only the drawn
filter is compiled; shadow code only for materials that shadow: ``shaders.MaterialVariant``).
``Renderer.created`` logs each GPU resource it builds, so tests (and curious users) can see exactly what a scene
cost.
"""

from __future__ import annotations

import contextlib
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np
import wgpu

from maptools.cache import cached_generate, serving
from wgpuviewer import camera as cam
from wgpuviewer import meshes, textures
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu, allocating, create_texture, format_bytes, mip_chain
from wgpuviewer.core.images import read_header
from wgpuviewer.core.structs import FragmentOutputs
from wgpuviewer.core.wgsl import Generated
from wgpuviewer.scene import SHADOW_MODES, Camera, Scene
from wgpuviewer.techniques import Technique, get_technique, resolve_params

from . import autotable
from .filters import (
    DEFAULT_DERIVATIVES,
    DEFAULT_FILTER,
    FILTER_GROUP,
    get_derivatives,
    get_filter,
    pack_filter_params,
    resolve_filter_params,
    sampler_descriptor,
)
from .maps import MAP_SLOTS, PARAMS_BINDING, SAMPLER_BINDING, binding, depth_range, layout_entries
from .probe import probe
from .shaders import (
    FRAME,
    LIGHT,
    MAX_LIGHTS,
    OBJECT,
    PLAIN,
    MaterialVariant,
    compose_technique,
    pack_trace_params,
    trace_params_size,
    traces_relief,
)

COLOR_FORMAT = "rgba8unorm-srgb"  # offscreen colour: shaders write linear, PNGs get sRGB bytes
DATA_FORMAT = "rgba32uint"  # offscreen raw trace data (float bits): hit u, v, depth, fetches
LAYERS_FORMAT = "r32uint"  # offscreen: depth layers the search used per pixel
FILTER_FORMAT = "rgba32uint"  # offscreen: the filter's texels, depth fetches, hidden | flags << 24, ratio bits
VIEW_DEPTH_FORMAT = "r32uint"  # offscreen: camera depth of the traced hit (float bits)
DEPTH_FORMAT = "depth32float"
#: The targets of an offscreen render, in order: fs_data's outputs (generated into the render module) and their
#: formats. Raw values travel as float bits in 32-bit integer targets: float32 targets are not renderable
#: everywhere (OpenGL ES), 32-bit integer ones are.
DATA_OUT = FragmentOutputs("DataOut", [
    ("color", "vec4f", COLOR_FORMAT),
    ("data", "vec4u", DATA_FORMAT),  # fetches negative: capped
    ("layers", "u32", LAYERS_FORMAT),
    ("filtering", "vec4u", FILTER_FORMAT),
    ("view_depth", "u32", VIEW_DEPTH_FORMAT),
])
OFFSCREEN_FORMATS = DATA_OUT.formats


def hit_depth_outputs(outputs: FragmentOutputs) -> Generated:
    """``outputs``' struct as ``NAMEHitDepth`` with the depth builtin after its targets: the output of the entry
    points of depth_offset materials (``fs_data_hit_depth``), the targets from the same list."""
    lines = outputs.wgsl().rstrip("\n").split("\n")
    name = f"{outputs.name}HitDepth"
    lines[0] = f"struct {name} {{"
    lines.insert(-1, "    @builtin(frag_depth) frag_depth: f32,")
    return Generated(f"<generated: struct {name}>", "\n".join(lines) + "\n")

#: Bytes per pixel of the offscreen targets and the depth attachment.
_PIXEL_BYTES = {"rgba8unorm-srgb": 4, "rgba32uint": 16, "r32uint": 4, "depth32float": 4}
#: What a user can do about a frame too large for the adapter.
SMALLER_FRAME = "use a smaller size"

#: Frame.mode values (render.wgsl's MODE_* constants; "depth" draws its own entry point, fs_view_depth).
MODES = {"color": 0, "cost": 1, "uv": 2, "layer_depth": 3, "layers": 4, "albedo": 5, "depth": 6}

#: Draw configurations whose uniform buffer and bind group are kept per material (the least recently drawn are
#: dropped): draws with different parameters can share one submit (the A/B split, the benchmark's batched frames).
MAX_DRAW_GROUPS = 64

#: Formats of the material textures the renderer loads itself (the height-derived ones come from maps.py).
_MATERIAL_FORMATS = {"albedo": "rgba16float", "normal": "rgba8unorm"}


@dataclass(frozen=True)
class DrawConfig:
    """What one draw shows: a technique, all its parameter values, optionally a relief depth (UV units) to
    trace at instead of each material's own ``height_scale``, and the texture filter (``relief.filters``) with
    all its parameter values and the derivative source it is given. Build it with ``DrawConfig.of`` (checks
    the parameters against the registries) or ``Renderer.config`` (starts from the scene's parameters)."""

    technique: str
    params: tuple[tuple[str, object], ...]  # (name, value) for every parameter of the technique
    height_scale: float | None = None
    filter: str = DEFAULT_FILTER
    filter_params: tuple[tuple[str, object], ...] = ()  # (name, value) for every parameter of the filter
    derivatives: str = DEFAULT_DERIVATIVES
    #: Self-shadowing for every material (scene.SHADOW_MODES), overriding each material's ``shadows``; None: each
    #: material's own.
    shadows: str | None = None
    #: Depth offset for every material, overriding each material's ``depth_offset``; None: each material's own.
    depth_offset: bool | None = None

    @classmethod
    def of(cls, technique: str, params: dict | None = None, height_scale: float | None = None, *,
           filter: str = DEFAULT_FILTER, filter_params: dict | None = None,
           derivatives: str = DEFAULT_DERIVATIVES, shadows: str | None = None,
           depth_offset: bool | None = None) -> DrawConfig:
        t = get_technique(technique)
        f = get_filter(filter)
        if shadows is not None and shadows not in SHADOW_MODES:
            raise UserError(f"shadows = {shadows!r}; expected one of {', '.join(SHADOW_MODES)}")
        if depth_offset not in (None, True, False):
            raise UserError(f"depth_offset = {depth_offset!r}; expected true, false or none (each material's own)")
        return cls(t.name, tuple(resolve_params(t, params).items()), height_scale, f.name,
                   tuple(resolve_filter_params(f, filter_params).items()), get_derivatives(derivatives).name,
                   shadows, depth_offset)

    @property
    def values(self) -> dict:
        """The parameter values as a dict (a copy)."""
        return dict(self.params)

    @property
    def filter_values(self) -> dict:
        """The filter's parameter values (defaults for any not given)."""
        return {**get_filter(self.filter).defaults(), **dict(self.filter_params)}

    @property
    def label(self) -> str:
        """Technique, filter and derivative source, e.g. 'pom / ewa_vis (displaced)'."""
        return f"{self.technique} / {self.filter} ({self.derivatives})"


@dataclass
class OffscreenImage:
    color: np.ndarray  # (H, W, 4) uint8, sRGB; alpha 0 where nothing was drawn
    data: np.ndarray  # (H, W, 4) float32: hit u, hit v, hit depth, fetches (negative: capped)
    layers: np.ndarray | None = None  # (H, W) uint32: depth layers the search used (0: no layers)
    layer_range: tuple[float, float] = (0.0, 1.0)  # the layers mode's grey: (N - lo) / (hi - lo)
    #: (H, W, 4) uint32: texels the filter read, depth fetches of its visibility traces and slopes,
    #: hidden texels | flags << 24 (filters.FLAGS), the derivative source's raw length ratio as float32 bits.
    filter: np.ndarray | None = None
    #: (H, W) float32: camera depth of the traced hit, the distance from the camera along its view axis in scene
    #: units (linear view-space depth, not the depth buffer's reversed-Z value).
    view_depth: np.ndarray | None = None

    @property
    def covered(self) -> np.ndarray:
        return self.color[:, :, 3] > 0


class Renderer:
    def __init__(self, scene: Scene, gpu: Gpu, like: Renderer | None = None):
        """``like``: a renderer of a scene with the same materials (the benchmark's views of one height map) whose
        material textures, bind-group layouts, sampler and pipelines this one shares instead of building its own."""
        self.scene = scene
        self.gpu = gpu
        self.created: list[str] = []  # GPU resources built, in order: "kind:name"
        self._material_groups: OrderedDict[tuple, tuple[wgpu.GPUBindGroup, wgpu.GPUBuffer]] = OrderedDict()
        self._filter_groups: dict[tuple, wgpu.GPUBindGroup] = {}
        device = gpu.device
        U = wgpu.BufferUsage
        V, F = wgpu.ShaderStage.VERTEX, wgpu.ShaderStage.FRAGMENT
        if like is not None:
            self._textures, self._pipelines, self._material_layouts = like._textures, like._pipelines, like._material_layouts
            self._frame_layout, self._object_layout, self._sampler = like._frame_layout, like._object_layout, like._sampler
            self._clamp_sampler = like._clamp_sampler
            self._filter_layout, self._samplers = like._filter_layout, like._samplers
            self._depth_ranges = like._depth_ranges
        else:
            self._textures: dict[tuple[str, str], wgpu.GPUTexture] = {}
            self._depth_ranges: dict[str, tuple[float, float]] = {}
            self._pipelines: dict[tuple, wgpu.GPURenderPipeline] = {}
            self._material_layouts: dict[tuple[str, ...], wgpu.GPUBindGroupLayout] = {}
            self._frame_layout = device.create_bind_group_layout(
                label="frame", entries=[{"binding": 0, "visibility": V | F, "buffer": {"type": "uniform"}}]
            )
            self._object_layout = device.create_bind_group_layout(
                label="object", entries=[{"binding": 0, "visibility": V | F, "buffer": {"type": "uniform"}}]
            )
            self._sampler = device.create_sampler(
                label="material", address_mode_u="repeat", address_mode_v="repeat",
                mag_filter="linear", min_filter="linear", mipmap_filter="linear", max_anisotropy=1,
            )
            # address = "clamp" materials: the uv square is the relief's extent
            self._clamp_sampler = device.create_sampler(
                label="material:clamp", address_mode_u="clamp-to-edge", address_mode_v="clamp-to-edge",
                mag_filter="linear", min_filter="linear", mipmap_filter="linear", max_anisotropy=1,
            )
            self._filter_layout = device.create_bind_group_layout(
                label="filter", entries=[{"binding": 0, "visibility": F, "buffer": {"type": "uniform"}},
                                         {"binding": 1, "visibility": F, "sampler": {"type": "filtering"}}]
            )
            self._samplers: dict[tuple, wgpu.GPUSampler] = {}
        self._frame_buffer = device.create_buffer(label="frame", size=FRAME.size, usage=U.UNIFORM | U.COPY_DST)
        self._lights = scene_lights(scene)  # fixed for the scene: packed once, not per frame
        self._frame_group = device.create_bind_group(
            layout=self._frame_layout, entries=[{"binding": 0, "resource": {"buffer": self._frame_buffer}}]
        )
        self._objects = [self._build_object(i, obj) for i, obj in enumerate(scene.objects)]

    # --- scene geometry (every technique needs it) -------------------------------------------

    def _build_object(self, index: int, obj):
        device = self.gpu.device
        vertices = meshes.for_object(obj)
        vbuf = device.create_buffer_with_data(label=f"mesh:{index}", data=vertices, usage=wgpu.BufferUsage.VERTEX)
        model = cam.translation(obj.position) @ cam.rotation_xyz(obj.rotation)
        normal_matrix = np.eye(4)
        normal_matrix[:3, :3] = np.linalg.inv(model[:3, :3]).T
        material = self.scene.materials[obj.material]
        data = OBJECT.pack({"model": cam.to_wgsl(model), "normal_matrix": cam.to_wgsl(normal_matrix),
                            "uv_transform": [*material.uv_scale, *offset_fraction(material.uv_offset)]})
        ubuf = device.create_buffer_with_data(label=f"object:{index}", data=data, usage=wgpu.BufferUsage.UNIFORM)
        group = device.create_bind_group(layout=self._object_layout, entries=[{"binding": 0, "resource": {"buffer": ubuf}}])
        return obj.material, vbuf, len(vertices), group

    # --- lazily built material resources -----------------------------------------------------

    def missing(self, technique: str) -> list[tuple[str, str]]:
        """(material, slot) of the textures drawing ``technique`` needs and the renderer has not built yet."""
        t = get_technique(technique)
        used = dict.fromkeys(m for m, *_ in self._objects)  # scene order, each once
        return [(m, k) for m in used for k in t.textures if (m, k) not in self._textures]

    def prepare(self, technique: str, progress: Callable[[str, int, int], None] | None = None) -> None:
        """Build every texture ``technique`` needs now (loading files, deriving maps), reporting each step as
        ``progress(label, done, total)``: what ``render``/``encode`` would otherwise build on first use. The
        viewer calls it from a worker thread while it keeps drawing; problems raise UserError naming the key."""
        todo = self.missing(technique)
        for material, kind in todo:  # all refused before any is loaded or generated
            self.check_map(material, kind)
        for done, (material, kind) in enumerate(todo):
            if progress is not None:
                progress(f"{material}.{kind}", done, len(todo))
            self.texture(material, kind)
        if progress is not None:
            progress("done", len(todo), len(todo))

    def check_map(self, material_name: str, kind: str) -> None:
        """Refuse slot ``kind`` of a material when its height map's size (a file's header, a builtin's size: nothing
        is loaded) is beyond what the map can be built at on this adapter (``MapSlot.check``): a UserError
        against the scene's height key. Slots without a check (the material's own textures) pass."""
        slot = MAP_SLOTS[kind]
        if slot.check is not None:
            material = self.scene.materials[material_name]
            with _reported_against(material.height, kind):
                slot.check(self.gpu, *_height_size(material))

    def texture(self, material_name: str, kind: str) -> wgpu.GPUTexture:
        """The GPU texture of slot ``kind`` (maps.MAP_SLOTS) of a material, built on first use."""
        key = (material_name, kind)
        if key not in self._textures:
            material = self.scene.materials[material_name]
            label = f"{material_name}.{kind}"
            slot = MAP_SLOTS[kind]
            if slot.derived:
                self.check_map(material_name, kind)
                depth = self._depth_data(material)
                if material_name not in self._depth_ranges:  # while the depth is loaded anyway
                    self._depth_ranges[material_name] = depth_range(depth, self.gpu.depth_format)
                measured = (probe,) if slot.measured else ()  # auto's table: measured with the probe
                with _building(material, kind):
                    self._textures[key] = slot.build(self.gpu, depth, material.height_scale, label, *measured)
            else:
                if kind == "normal":
                    data = self._normal_data(material)  # our own copy: encoded in place, n * 0.5 + 0.5
                    data *= 0.5
                    data += 0.5
                    source = material.normal or material.height
                else:
                    data = textures.load_albedo(material.albedo)
                    source = material.albedo
                with _reported_against(source, kind):
                    self._textures[key] = create_texture(self.gpu, mip_chain(data), _MATERIAL_FORMATS[kind], label)
                del data
            self.created.append(f"texture:{label}")
        return self._textures[key]

    def depth_range(self, material_name: str) -> tuple[float, float]:
        """The range of a material's depth texture (maps.depth_range), computed once."""
        if material_name not in self._depth_ranges:
            material = self.scene.materials[material_name]
            self._depth_ranges[material_name] = depth_range(self._depth_data(material), self.gpu.depth_format)
        return self._depth_ranges[material_name]

    def auto_table(self, material_name: str) -> np.ndarray:
        """auto's measurements on a material (relief/autotable.py): from the disk cache once auto has drawn it."""
        material = self.scene.materials[material_name]
        return autotable.measure(self._depth_data(material), material.height_scale, probe)

    @staticmethod
    def _depth_data(material) -> np.ndarray:
        if material.height is None:  # no relief: the surface is the top plane
            return np.zeros((1, 1), np.float32)
        return textures.load_depth(material.height, material.height_is_depth)

    def _normal_data(self, material) -> np.ndarray:
        """Normals in the shader's tangent frame: x = u, y = v (image rows down)."""
        if material.normal is not None:
            normals = textures.load_normal_map(material.normal, material.normal_y).copy()
            normals[:, :, 1] *= -1  # OpenGL convention: +y points to image row 0, i.e. towards -v
            return normals
        if material.height is None:
            return np.array([[[0.0, 0.0, 1.0]]], np.float32)
        height = 1.0 - textures.load_depth(material.height, material.height_is_depth)
        self.created.append(f"map:{material.name}.normal")
        # Slopes of the actual relief: height_scale UV units deep over a texture width of 1 UV unit.
        # maptools' "directx" convention has +y towards increasing rows, which is +v here.
        strength = material.height_scale * height.shape[1]
        with _reported_against(material.height, "normal"):
            return cached_generate("normal", height, backend="cpu", strength=strength, y="directx")

    def _material_layout(self, technique: Technique) -> wgpu.GPUBindGroupLayout:
        if technique.textures not in self._material_layouts:
            F = wgpu.ShaderStage.FRAGMENT
            entries = [
                {"binding": PARAMS_BINDING, "visibility": F, "buffer": {"type": "uniform"}},
                {"binding": SAMPLER_BINDING, "visibility": F, "sampler": {"type": "filtering"}},
            ] + layout_entries(technique.textures, F)
            self._material_layouts[technique.textures] = self.gpu.device.create_bind_group_layout(
                label="material:" + "+".join(technique.textures), entries=entries
            )
        return self._material_layouts[technique.textures]

    def _material_group(self, material_name: str, technique: Technique, draw: DrawConfig):
        """Bind group and uniform buffer of one draw configuration on one material (its own buffer, so draws with
        other parameters recorded into the same submit keep theirs)."""
        key = (material_name, draw.technique, draw.params, draw.height_scale)
        if key in self._material_groups:
            self._material_groups.move_to_end(key)
            return self._material_groups[key]
        device = self.gpu.device
        params = device.create_buffer(
            label=f"params:{material_name}:{technique.name}",
            size=trace_params_size(technique),
            usage=wgpu.BufferUsage.UNIFORM | wgpu.BufferUsage.COPY_DST,
        )
        clamp = self.scene.materials[material_name].address == "clamp"
        entries = [{"binding": PARAMS_BINDING, "resource": {"buffer": params}},
                   {"binding": SAMPLER_BINDING, "resource": self._clamp_sampler if clamp else self._sampler}]
        entries += [
            {"binding": binding(t), "resource": self.texture(material_name, t).create_view()}
            for t in technique.textures
        ]
        group = device.create_bind_group(layout=self._material_layout(technique), entries=entries)
        self._material_groups[key] = (group, params)
        if len(self._material_groups) > MAX_DRAW_GROUPS:
            self._material_groups.popitem(last=False)
        return group, params

    def _filter_group(self, draw: DrawConfig) -> wgpu.GPUBindGroup:
        """The filter's uniform and sampler (group FILTER_GROUP), per filter and parameter values."""
        key = (draw.filter, draw.filter_params)
        if key not in self._filter_groups:
            f = get_filter(draw.filter)
            values = draw.filter_values
            descriptor = sampler_descriptor(f, values)
            sampler_key = tuple(sorted(descriptor.items()))
            if sampler_key not in self._samplers:
                self._samplers[sampler_key] = self.gpu.device.create_sampler(label=f"filter:{f.name}", **descriptor)
            buffer = self.gpu.device.create_buffer_with_data(
                label=f"filter:{f.name}", data=pack_filter_params(f, values), usage=wgpu.BufferUsage.UNIFORM
            )
            self._filter_groups[key] = self.gpu.device.create_bind_group(
                layout=self._filter_layout,
                entries=[{"binding": 0, "resource": {"buffer": buffer}},
                         {"binding": 1, "resource": self._samplers[sampler_key]}],
            )
        return self._filter_groups[key]

    def module(self, technique: Technique, filter: str = DEFAULT_FILTER, derivatives: str = DEFAULT_DERIVATIVES,
               variant: MaterialVariant = PLAIN):
        """The composed render module (``core.wgsl.Module``) of a technique with a filter, derivative source and
        material variant."""
        return compose_technique(technique, "render", filter, derivatives,
                                 records=(DATA_OUT.generated(), hit_depth_outputs(DATA_OUT)), variant=variant)

    def variant(self, material_name: str, technique: Technique, draw: DrawConfig) -> MaterialVariant:
        """The material variant a material is drawn with: its ``shadows`` and ``depth_offset`` (the draw's overrides
        first) and ``address``; shadows and the hit's depth only where the technique traces the relief."""
        material = self.scene.materials[material_name]
        traced = traces_relief(technique)
        shadows = material.shadows if draw.shadows is None else draw.shadows
        depth_offset = material.depth_offset if draw.depth_offset is None else draw.depth_offset
        return MaterialVariant(shadows if traced else "off", depth_offset and traced,
                               material.address == "clamp")

    def pipeline(self, technique: Technique, formats: tuple[str, ...], filter: str = DEFAULT_FILTER,
                 derivatives: str = DEFAULT_DERIVATIVES, mode: str = "color",
                 variant: MaterialVariant = PLAIN) -> wgpu.GPURenderPipeline:
        """The render pipeline of a technique with a filter, derivative source and material variant into
        ``formats``: one target draws ``fs_color`` (``fs_view_depth`` for ``mode`` "depth"), more draw ``fs_data``
        (OFFSCREEN_FORMATS); a depth_offset variant draws their ``_hit_depth`` entry points."""
        entry = fragment_entry(formats, mode, variant.depth_offset)
        key = (technique.name, filter, derivatives, formats, entry, variant)
        if key not in self._pipelines:
            device = self.gpu.device
            what = technique.name if (filter, derivatives) == (DEFAULT_FILTER, DEFAULT_DERIVATIVES) \
                else f"{technique.name}/{filter}/{derivatives}"
            what += variant.label
            label = f"render:{what}:{entry}:{'+'.join(formats)}"
            code = self.module(technique, filter, derivatives, variant).code
            module = device.create_shader_module(label=label, code=code)
            layout = device.create_pipeline_layout(
                label=label,
                bind_group_layouts=[self._frame_layout, self._material_layout(technique), self._object_layout,
                                    self._filter_layout],
            )
            self._pipelines[key] = device.create_render_pipeline(
                label=label,
                layout=layout,
                vertex={
                    "module": module,
                    "entry_point": "vs_main",
                    "buffers": [{"array_stride": meshes.VERTEX_STRIDE, "attributes": meshes.VERTEX_ATTRIBUTES}],
                },
                primitive={"topology": "triangle-list", "cull_mode": "back", "front_face": "ccw"},
                # Reversed Z (camera.perspective): 1 at near, 0 at far; the nearer surface has the greater depth.
                depth_stencil={"format": DEPTH_FORMAT, "depth_write_enabled": True, "depth_compare": "greater"},
                fragment={
                    "module": module,
                    "entry_point": entry,
                    "targets": [{"format": f} for f in formats],
                },
            )
            depth_view = mode == "depth" and len(formats) == 1
            self.created.append(f"pipeline:{what}:{'+'.join(formats)}" + (":depth" if depth_view else ""))
        return self._pipelines[key]

    # --- frames ------------------------------------------------------------------------------

    def rebuild_pipelines(self) -> list[tuple[Technique, str]]:
        """Compile every cached pipeline again from the WGSL files (hot reload). A pipeline that fails keeps
        its previous version; returns (technique, message) for each failure, the message located in the WGSL
        file (``file:line:column: reason``, core.wgsl.Module.locate)."""
        failures = []
        for key in list(self._pipelines):
            name, filter, derivatives, formats, entry, variant = key
            technique = get_technique(name)
            old = self._pipelines.pop(key)
            try:
                self.pipeline(technique, formats, filter, derivatives,
                              "depth" if entry.startswith("fs_view_depth") else "color", variant)
            except wgpu.GPUError as error:
                self._pipelines[key] = old
                try:
                    message = self.module(technique, filter, derivatives, variant).locate(str(error))
                except OSError as read_error:
                    message = str(read_error)
                failures.append((technique, message))
            except OSError as error:  # a WGSL file vanished mid-edit
                self._pipelines[key] = old
                failures.append((technique, str(error)))
        return failures

    def config(self, technique: str, params: dict | None = None, height_scale: float | None = None,
               **filtering) -> DrawConfig:
        """A DrawConfig for ``technique`` starting from the scene's parameters for it, ``params`` overriding;
        ``filtering``: DrawConfig.of's filter, filter_params, derivatives, shadows and depth_offset."""
        name = get_technique(technique).name
        return DrawConfig.of(name, {**self.scene.technique_params.get(name, {}), **(params or {})}, height_scale,
                             **filtering)

    def _write_frame(self, camera: Camera, size: tuple[int, int], mode: str, technique: Technique, params: dict):
        w, h = size
        view_proj = cam.perspective(camera.fov, w / h, camera.near, camera.far) @ cam.look_at(
            camera.position, camera.target, camera.up
        )
        lo, hi = technique.layer_range(params)
        data = FRAME.pack({"view_proj": cam.to_wgsl(view_proj), "camera_pos": [*camera.position, 0.0],
                           "light_count": len(self.scene.lights), "mode": MODES[mode],
                           "cost_scale": technique.cost_scale(params), "layer_lo": lo, "layer_hi": hi,
                           "lights": self._lights})
        self.gpu.device.queue.write_buffer(self._frame_buffer, 0, data)

    def encode(
        self,
        encoder: wgpu.GPUCommandEncoder,
        color_views: list,
        depth_view,
        formats: tuple[str, ...],
        draw: DrawConfig,
        camera: Camera,
        size: tuple[int, int],
        mode: str = "color",
        *,
        clear: bool = True,
        scissor: tuple[int, int, int, int] | None = None,
        timestamp_writes: dict | None = None,
    ) -> None:
        """Record one frame of ``draw`` into ``color_views`` (1 target: fs_color, which shows ``mode``; more: fs_data,
        the first of OFFSCREEN_FORMATS).

        ``clear=False`` keeps what the targets hold and ``scissor`` (x, y, w, h) limits the drawing:
        together they put several techniques side by side in one frame. ``timestamp_writes`` goes to
        the render pass as is (GPU timing).
        """
        technique = get_technique(draw.technique)
        params = draw.values
        self._write_frame(camera, size, mode, technique, params)
        filter_group = self._filter_group(draw)
        groups = {}
        for material_name in {m for m, *_ in self._objects}:
            group, params_buffer = self._material_group(material_name, technique, draw)
            material = self.scene.materials[material_name]
            depth_shape = self.texture(material_name, "depth").size[1::-1] if technique.needs_depth else (1, 1)
            depth_range = self.depth_range(material_name) if technique.needs_depth else (0.0, 1.0)
            height_scale = material.height_scale if draw.height_scale is None else draw.height_scale
            self.gpu.device.queue.write_buffer(
                params_buffer, 0, pack_trace_params(technique, height_scale, depth_shape, params, depth_range)
            )
            groups[material_name] = group
        background = [*self.scene.background, 0.0]
        attachments = [
            {
                "view": v, "load_op": "clear" if clear else "load", "store_op": "store",
                "clear_value": background if i == 0 else (0, 0, 0, 0),
            }
            for i, v in enumerate(color_views)
        ]
        rpass = encoder.begin_render_pass(
            label=f"frame:{technique.name}",
            color_attachments=attachments,
            depth_stencil_attachment={
                "view": depth_view, "depth_load_op": "clear", "depth_store_op": "discard", "depth_clear_value": 0.0,
            },
            timestamp_writes=timestamp_writes,
        )
        if scissor is not None:
            rpass.set_scissor_rect(*scissor)
        pipelines = {m: self.pipeline(technique, formats, draw.filter, draw.derivatives, mode,
                                      self.variant(m, technique, draw)) for m in groups}
        rpass.set_bind_group(0, self._frame_group)
        rpass.set_bind_group(FILTER_GROUP, filter_group)
        bound = None
        for material_name, vbuf, count, object_group in self._objects:
            if pipelines[material_name] is not bound:
                bound = pipelines[material_name]
                rpass.set_pipeline(bound)
            rpass.set_bind_group(1, groups[material_name])
            rpass.set_bind_group(2, object_group)
            rpass.set_vertex_buffer(0, vbuf)
            rpass.draw(count)
        rpass.end()

    def render(self, draw: DrawConfig | str, size: tuple[int, int], camera: Camera | None = None,
               mode: str = "color", *, size_name: str = "render size") -> OffscreenImage:
        """Draw offscreen and read back the colour, the raw trace data, the camera depth and the filter's
        statistics (every output mode is made from them: ``relief.output``). ``draw``: a
        DrawConfig, or a technique name (drawn with the scene's parameters for it). ``mode`` "albedo" makes the
        colour the filtered albedo, unlit; every other mode reads the shaded colour. A frame too large for the
        adapter (``check_frame_size``, or its memory) is a UserError naming ``size_name`` (the CLI: ``--size``)."""
        if isinstance(draw, str):
            draw = self.config(draw)
        check_frame_size(self.gpu, size, size_name)
        device = self.gpu.device
        w, h = size
        frame = f"{size_name} {w}x{h}"
        usage = wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC
        with allocating(self.gpu, frame, frame_bytes(size), SMALLER_FRAME):
            color = device.create_texture(label="offscreen:color", size=(w, h, 1), format=COLOR_FORMAT, usage=usage)
            data = device.create_texture(label="offscreen:data", size=(w, h, 1), format=DATA_FORMAT, usage=usage)
            layers = device.create_texture(label="offscreen:layers", size=(w, h, 1), format=LAYERS_FORMAT,
                                           usage=usage)
            stats = device.create_texture(label="offscreen:filter", size=(w, h, 1), format=FILTER_FORMAT,
                                          usage=usage)
            view_depth = device.create_texture(label="offscreen:view_depth", size=(w, h, 1),
                                               format=VIEW_DEPTH_FORMAT, usage=usage)
            depth = device.create_texture(label="offscreen:depth", size=(w, h, 1), format=DEPTH_FORMAT,
                                          usage=wgpu.TextureUsage.RENDER_ATTACHMENT)
        encoder = device.create_command_encoder(label="offscreen")
        self.encode(
            encoder, [color.create_view(), data.create_view(), layers.create_view(), stats.create_view(),
                      view_depth.create_view()],
            depth.create_view(), OFFSCREEN_FORMATS, draw,
            camera or self.scene.camera, size, "albedo" if mode == "albedo" else "color",
        )
        device.queue.submit([encoder.finish()])
        with allocating(self.gpu, f"reading back {frame}", readback_bytes(w, h, DATA_FORMAT), SMALLER_FRAME):
            return OffscreenImage(
                color=_read_texture(device, color, 4, np.uint8),
                data=_read_texture(device, data, 4, np.uint32).view(np.float32),
                layers=_read_texture(device, layers, 1, np.uint32)[:, :, 0],
                layer_range=get_technique(draw.technique).layer_range(draw.values),
                filter=_read_texture(device, stats, 4, np.uint32),
                view_depth=_read_texture(device, view_depth, 1, np.uint32)[:, :, 0].view(np.float32),
            )


def frame_bytes(size: tuple[int, int]) -> int:
    """GPU memory of an offscreen frame of ``size``: its targets and depth attachment."""
    w, h = size
    return w * h * sum(_PIXEL_BYTES[f] for f in (*OFFSCREEN_FORMATS, DEPTH_FORMAT))


def readback_bytes(w: int, h: int, fmt: str) -> int:
    """Bytes of the buffer a w x h target of ``fmt`` is read back through: rows padded to 256 bytes and the whole
    to 4096, as wgpu's ``read_texture`` makes it."""
    row = -(-w * _PIXEL_BYTES[fmt] // 256) * 256
    return -(-row * h // 4096) * 4096


def check_frame_size(gpu: Gpu, size: tuple[int, int], size_name: str = "render size") -> None:
    """Refuse an offscreen frame of ``size`` the adapter cannot make or read back, before anything is loaded or
    drawn: a side beyond its 2D texture limit, or a target whose read-back buffer is beyond its largest buffer.
    The UserError names ``size_name`` (the option the size came from) and the largest frame of that shape that
    fits."""
    w, h = size
    limits = gpu.device.limits
    side = limits["max-texture-dimension-2d"]
    if max(w, h) > side:
        raise UserError(f"{size_name} {w}x{h}: larger than this adapter's limit of {side} pixels per side; "
                        f"use at most {side} per side")
    largest = limits["max-buffer-size"]
    fmt = max(OFFSCREEN_FORMATS, key=lambda f: readback_bytes(w, h, f))
    need = readback_bytes(w, h, fmt)
    if need > largest:
        scale = (largest / need) ** 0.5
        fw, fh = max(1, int(w * scale)), max(1, int(h * scale))
        while readback_bytes(fw, fh, fmt) > largest:  # the row padding: shrink a little more
            fw, fh = max(1, fw - 1 - fw // 100), max(1, fh - 1 - fh // 100)
        raise UserError(f"{size_name} {w}x{h}: its {fmt} target is read back through a {format_bytes(need)} "
                        f"buffer, more than this adapter's largest buffer of {format_bytes(largest)}; use at most "
                        f"{fw}x{fh}")


def _height_size(material) -> tuple[int, int]:
    """(width, height) of a material's height map without loading it: a builtin's size, a file's header; (1, 1)
    without one (the renderer's flat depth)."""
    ref = material.height
    if ref is None:
        return 1, 1
    if ref.kind == "file":
        with textures.reported_against(ref):
            header = read_header(ref.path)
        return header.width, header.height
    return tuple(ref.size)


@contextlib.contextmanager
def _building(material, kind: str):
    """Around the build of a material's derived map ``kind``: the maps the scene names for the material
    (``Material.maps``) are served from their files (``maptools.cache.serving``), and problems are reported against
    the height map's key, except a named map's, whose messages name its own key."""
    named = {slot: (ref.path, ref.origin) for slot, ref in material.maps}
    with _reported_against(None if kind in named else material.height, kind), serving(named):
        yield


@contextlib.contextmanager
def _reported_against(ref, kind: str):
    """A texture of slot ``kind`` that cannot be built (too large for a limit or for the adapter's memory, ...) is
    reported against the scene key of the texture it comes from (``ref``; the height map for a derived map), not
    against the map the user never named."""
    try:
        yield
    except UserError as error:
        if ref is None or not ref.origin:
            raise
        raise ref.error(f"its {kind} map cannot be built: {error}") from None


def fragment_entry(formats: tuple[str, ...], mode: str, hit_depth: bool = False) -> str:
    """The fragment entry point of render.wgsl that draws into ``formats`` in ``mode``; ``hit_depth``: the one
    that also writes the traced hit's depth (depth_offset materials)."""
    entry = "fs_data" if len(formats) > 1 else "fs_view_depth" if mode == "depth" else "fs_color"
    return entry + "_hit_depth" if hit_depth else entry


def offset_fraction(uv_offset: tuple[float, float]) -> tuple[float, float]:
    """``Material.uv_offset`` less its whole tiles, in float64 (``x - floor(x)``: exact for x >= 0, within 2^-53
    below), in [0, 1]. The materials repeat, so whole tiles move nothing; what reaches the GPU's float32 is the
    fraction alone, and an offset of 1e5 tiles draws exactly what its fraction draws."""
    offset = np.asarray(uv_offset, np.float64)
    return tuple(float(x) for x in offset - np.floor(offset))


def scene_lights(scene) -> np.ndarray:
    """The Frame uniform's light records (LIGHT, MAX_LIGHTS of them; unused ones zero) for ``scene``'s lights."""
    lights = np.zeros(MAX_LIGHTS, LIGHT.dtype)
    for i, light in enumerate(scene.lights):  # the scene checked the count (MAX_LIGHTS)
        if light.kind == "directional":
            lights["vector"][i] = [*(-np.asarray(light.direction)), 0.0]  # towards the light
        else:
            lights["vector"][i] = [*light.position, 1.0]
        lights["color"][i] = [*(np.asarray(light.color) * light.intensity), 0.0]
    return lights


def _read_texture(device, texture, channels: int, dtype) -> np.ndarray:
    w, h = texture.size[:2]
    row = w * channels * np.dtype(dtype).itemsize
    raw = device.queue.read_texture(
        {"texture": texture, "mip_level": 0, "origin": (0, 0, 0)},
        {"offset": 0, "bytes_per_row": row, "rows_per_image": h},
        (w, h, 1),
    )
    return np.frombuffer(raw, dtype).reshape(h, w, channels).copy()
