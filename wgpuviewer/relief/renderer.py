"""Drawing a scene with one technique, into a window surface or offscreen.

What to draw comes per draw as a frozen ``DrawConfig`` (the registry's ``Technique``, its parameters, a height-scale override, the
texture filter with its parameters and the derivative source it is given); the renderer holds no per-technique
state of its own beyond caches. Everything is built lazily from what the drawn technique needs ("model only what
a scene needs"): a material's depth texture exists only once a technique that traces depth is drawn, pipelines are
compiled on first use and cached per technique x filter x derivative source x material variant (only the drawn
filter is compiled; shadow code only for materials that shadow: ``shaders.MaterialVariant``).
``Renderer.created`` logs each GPU resource it builds, so tests (and curious users) can see exactly what a scene
cost.

Its parts, by job: ``material_textures`` (a material's textures and derived maps, built on first use),
``uniforms`` (the Frame, Object and Light records packed from the scene), ``pipelines`` (bind-group layouts,
samplers, the compiled pipelines, hot reload), ``targets`` (the offscreen frame: its targets, size limits and
read-back). This module holds the draw: each configuration's bind groups and the render pass it records.
"""

from __future__ import annotations

import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass, field

import wgpu

from wgpuviewer import meshes
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu
from wgpuviewer.core.params import resolve_params
from wgpuviewer.scene import SHADOW_MODES, Camera, Scene
from wgpuviewer.techniques import Technique, get_technique

from .filters import (
    DEFAULT_DERIVATIVES,
    DEFAULT_FILTER,
    FILTER_GROUP,
    get_derivatives,
    get_filter,
    pack_filter_params,
    resolve_filter_params,
)
from .maps import MAP_SLOTS, PARAMS_BINDING, SAMPLER_BINDING, binding, depth_range
from .material_textures import depth_data, derived_texture, height_size, material_texture, reported_against
from .pipelines import Pipelines, module
from .shaders import FRAME, PLAIN, MaterialVariant, material_variant, pack_trace_params, trace_params_size
from .targets import (
    OFFSCREEN_FORMATS,
    OffscreenFrame,
    OffscreenImage,
    check_frame_size,
)
from .uniforms import frame_data, object_data, scene_lights

#: Draw configurations whose uniform buffer and bind group are kept per material (the least recently drawn are
#: dropped): draws with different parameters can share one submit (the A/B split, the benchmark's batched frames).
MAX_DRAW_GROUPS = 64


@dataclass(frozen=True)
class DrawConfig:
    """What one draw shows: a technique (the registry's ``Technique``), all its parameter values, optionally a
    relief depth (UV units) to trace at instead of each material's own ``height_scale``, and the texture filter
    (``relief.filters``) with all its parameter values and the derivative source it is given. Build it with
    ``DrawConfig.of`` (checks the parameters against the registries) or ``Renderer.config`` (starts from the
    scene's parameters)."""

    technique: Technique = field(hash=False)  # equal configurations hash alike by the other fields
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
    def of(cls, technique: Technique | str, params: dict | None = None, height_scale: float | None = None, *,
           filter: str = DEFAULT_FILTER, filter_params: dict | None = None,
           derivatives: str = DEFAULT_DERIVATIVES, shadows: str | None = None,
           depth_offset: bool | None = None) -> DrawConfig:
        """``technique``: a registry entry, or its name (looked up here, once)."""
        t = technique if isinstance(technique, Technique) else get_technique(technique)
        f = get_filter(filter)
        if shadows is not None and shadows not in SHADOW_MODES:
            raise UserError(f"shadows = {shadows!r}; expected one of {', '.join(SHADOW_MODES)}")
        if depth_offset not in (None, True, False):
            raise UserError(f"depth_offset = {depth_offset!r}; expected true, false or none (each material's own)")
        return cls(t, tuple(resolve_params(t, params).items()), height_scale, f.name,
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
        return f"{self.technique.name} / {self.filter} ({self.derivatives})"


class Renderer:
    def __init__(self, scene: Scene, gpu: Gpu, like: Renderer | None = None):
        """``like``: a renderer of a scene with the same materials (the benchmark's views of one height map) whose
        material textures, bind-group layouts, samplers and pipelines this one shares instead of building its own."""
        self.scene = scene
        self.gpu = gpu
        self.created: list[str] = []  # GPU resources built, in order: "kind:name"
        self._building = threading.Lock()  # prepare: one thread builds the maps, others wait for them
        self._material_groups: OrderedDict[tuple, tuple[wgpu.GPUBindGroup, wgpu.GPUBuffer]] = OrderedDict()
        self._filter_groups: dict[tuple, wgpu.GPUBindGroup] = {}
        if like is not None:
            self.pipelines, self._textures, self._depth_ranges = like.pipelines, like._textures, like._depth_ranges
        else:
            self.pipelines = Pipelines(gpu)
            self._textures: dict[tuple[str, str], wgpu.GPUTexture] = {}
            self._depth_ranges: dict[str, tuple[float, float]] = {}
        device = gpu.device
        U = wgpu.BufferUsage
        self._frame_buffer = device.create_buffer(label="frame", size=FRAME.size, usage=U.UNIFORM | U.COPY_DST)
        self._lights = scene_lights(scene)  # fixed for the scene: packed once, not per frame
        self._frame_group = device.create_bind_group(
            layout=self.pipelines.frame_layout, entries=[{"binding": 0, "resource": {"buffer": self._frame_buffer}}]
        )
        self._objects = [self._build_object(i, obj) for i, obj in enumerate(scene.objects)]

    @property
    def _pipelines(self) -> dict[tuple, wgpu.GPURenderPipeline]:
        """The pipeline cache: (technique name, filter, derivatives, formats, entry, variant) -> pipeline."""
        return self.pipelines.cache

    # --- scene geometry (every technique needs it) -------------------------------------------

    def _build_object(self, index: int, obj):
        device = self.gpu.device
        vertices = meshes.for_object(obj)
        vbuf = device.create_buffer_with_data(label=f"mesh:{index}", data=vertices, usage=wgpu.BufferUsage.VERTEX)
        data = object_data(obj, self.scene.materials[obj.material])
        ubuf = device.create_buffer_with_data(label=f"object:{index}", data=data, usage=wgpu.BufferUsage.UNIFORM)
        group = device.create_bind_group(layout=self.pipelines.object_layout,
                                         entries=[{"binding": 0, "resource": {"buffer": ubuf}}])
        return obj.material, vbuf, len(vertices), group

    # --- lazily built material resources -----------------------------------------------------

    def missing(self, technique: Technique | str) -> list[tuple[str, str]]:
        """(material, slot) of the textures drawing ``technique`` (an entry or its name) needs and the renderer has
        not built yet."""
        t = technique if isinstance(technique, Technique) else get_technique(technique)
        used = dict.fromkeys(m for m, *_ in self._objects)  # scene order, each once
        return [(m, k) for m in used for k in t.textures if (m, k) not in self._textures]

    def prepare(self, technique: Technique | str, progress: Callable[[str, int, int], None] | None = None) -> None:
        """Build every texture ``technique`` needs now (loading files, deriving maps), reporting each step as
        ``progress(label, done, total)``: what ``render``/``encode`` would otherwise build on first use. The
        viewer calls it from a worker thread while it keeps drawing; problems raise UserError naming the key."""
        with self._building:  # threads preparing one renderer build each map once
            self._prepare(technique, progress)

    def _prepare(self, technique: Technique | str, progress: Callable[[str, int, int], None] | None) -> None:
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
            with reported_against(material.height, kind):
                slot.check(self.gpu, *height_size(material))

    def texture(self, material_name: str, kind: str) -> wgpu.GPUTexture:
        """The GPU texture of slot ``kind`` (maps.MAP_SLOTS) of a material, built on first use."""
        key = (material_name, kind)
        if key not in self._textures:
            material = self.scene.materials[material_name]
            label = f"{material_name}.{kind}"
            if MAP_SLOTS[kind].derived:
                self.check_map(material_name, kind)
                depth = depth_data(material)
                if material_name not in self._depth_ranges:  # while the depth is loaded anyway
                    self._depth_ranges[material_name] = depth_range(depth, self.gpu.depth_format)
                self._textures[key] = derived_texture(self.gpu, material, kind, depth, label)
            else:
                self._textures[key] = material_texture(self.gpu, material, kind, label, self.created)
            self.created.append(f"texture:{label}")
        return self._textures[key]

    def depth_range(self, material_name: str) -> tuple[float, float]:
        """The range of a material's depth texture (maps.depth_range), computed once."""
        if material_name not in self._depth_ranges:
            material = self.scene.materials[material_name]
            self._depth_ranges[material_name] = depth_range(depth_data(material), self.gpu.depth_format)
        return self._depth_ranges[material_name]

    # --- bind groups of a draw ---------------------------------------------------------------

    def _material_group(self, material_name: str, draw: DrawConfig):
        """Bind group and uniform buffer of one draw configuration on one material (its own buffer, so draws with
        other parameters recorded into the same submit keep theirs)."""
        technique = draw.technique
        key = (material_name, technique.name, draw.params, draw.height_scale)
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
        sampler = self.pipelines.clamp_sampler if clamp else self.pipelines.sampler
        entries = [{"binding": PARAMS_BINDING, "resource": {"buffer": params}},
                   {"binding": SAMPLER_BINDING, "resource": sampler}]
        entries += [
            {"binding": binding(t), "resource": self.texture(material_name, t).create_view()}
            for t in technique.textures
        ]
        group = device.create_bind_group(layout=self.pipelines.material_layout(technique), entries=entries)
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
            sampler = self.pipelines.filter_sampler(f, values)
            buffer = self.gpu.device.create_buffer_with_data(
                label=f"filter:{f.name}", data=pack_filter_params(f, values), usage=wgpu.BufferUsage.UNIFORM
            )
            self._filter_groups[key] = self.gpu.device.create_bind_group(
                layout=self.pipelines.filter_layout,
                entries=[{"binding": 0, "resource": {"buffer": buffer}}, {"binding": 1, "resource": sampler}],
            )
        return self._filter_groups[key]

    # --- pipelines ---------------------------------------------------------------------------

    def module(self, technique: Technique, filter: str = DEFAULT_FILTER, derivatives: str = DEFAULT_DERIVATIVES,
               variant: MaterialVariant = PLAIN):
        """The composed render module of a technique (``pipelines.module``)."""
        return module(technique, filter, derivatives, variant)

    def variant(self, material_name: str, technique: Technique, draw: DrawConfig) -> MaterialVariant:
        """The material variant a material is drawn with: its ``shadows`` and ``depth_offset`` (the draw's overrides
        first) and ``address``; shadows and the hit's depth only where the technique traces the relief; the technique's code
        paths the material's parameters run (``shaders.material_variant``)."""
        material = self.scene.materials[material_name]
        shadows = material.shadows if draw.shadows is None else draw.shadows
        depth_offset = material.depth_offset if draw.depth_offset is None else draw.depth_offset
        return material_variant(technique, material, draw.values, shadows, depth_offset)

    def pipeline(self, technique: Technique, formats: tuple[str, ...], filter: str = DEFAULT_FILTER,
                 derivatives: str = DEFAULT_DERIVATIVES, mode: str = "color",
                 variant: MaterialVariant = PLAIN) -> wgpu.GPURenderPipeline:
        """The render pipeline of a technique into ``formats`` (``Pipelines.pipeline``), compiled on first use."""
        return self.pipelines.pipeline(technique, formats, filter, derivatives, mode, variant, self.created)

    def rebuild_pipelines(self) -> list[tuple[Technique, str]]:
        """Compile every cached pipeline again from the WGSL files (hot reload): ``Pipelines.rebuild``."""
        return self.pipelines.rebuild(self.created)

    # --- frames ------------------------------------------------------------------------------

    def config(self, technique: Technique | str, params: dict | None = None, height_scale: float | None = None,
               **filtering) -> DrawConfig:
        """A DrawConfig for ``technique`` (an entry or its name) starting from the scene's parameters for it,
        ``params`` overriding; ``filtering``: DrawConfig.of's filter, filter_params, derivatives, shadows and
        depth_offset."""
        t = technique if isinstance(technique, Technique) else get_technique(technique)
        return DrawConfig.of(t, {**self.scene.technique_params.get(t.name, {}), **(params or {})}, height_scale,
                             **filtering)

    def _write_params(self, draw: DrawConfig) -> dict[str, wgpu.GPUBindGroup]:
        """Each material's group 1 for ``draw``, its TraceParams written."""
        technique, params = draw.technique, draw.values
        groups = {}
        for material_name in {m for m, *_ in self._objects}:
            group, params_buffer = self._material_group(material_name, draw)
            material = self.scene.materials[material_name]
            depth_shape = self.texture(material_name, "depth").size[1::-1] if technique.needs_depth else (1, 1)
            depth_range = self.depth_range(material_name) if technique.needs_depth else (0.0, 1.0)
            height_scale = material.height_scale if draw.height_scale is None else draw.height_scale
            self.gpu.device.queue.write_buffer(
                params_buffer, 0, pack_trace_params(technique, height_scale, depth_shape, params, depth_range)
            )
            groups[material_name] = group
        return groups

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
        technique = draw.technique
        self.gpu.device.queue.write_buffer(
            self._frame_buffer, 0, frame_data(self.scene, self._lights, camera, size, mode, technique, draw.values))
        filter_group = self._filter_group(draw)
        groups = self._write_params(draw)
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

    def render(self, draw: DrawConfig | Technique | str, size: tuple[int, int], camera: Camera | None = None,
               mode: str = "color", *, size_name: str = "render size") -> OffscreenImage:
        """Draw offscreen and read back the colour, the raw trace data, the camera depth and the filter's
        statistics (every output mode is made from them: ``relief.output``). ``draw``: a DrawConfig, or a technique
        (an entry or its name: drawn with the scene's parameters for it). ``mode`` "albedo" makes the colour the
        filtered albedo, unlit; every other mode reads the shaded colour. A frame too large for the adapter
        (``check_frame_size``, or its memory) is a FrameError naming ``size_name``. Safe from several threads:
        frames on one device are drawn one at a time (``Gpu.lock``)."""
        if not isinstance(draw, DrawConfig):
            draw = self.config(draw)
        check_frame_size(self.gpu, size, size_name)
        # The frame and params uniforms are the renderer's, written by encode and read when the submit runs: a
        # draw of another thread in between would change this one's camera. The device's lock holds the whole
        # frame, from the writes to the read-back.
        with self.gpu.lock:
            frame = OffscreenFrame(self.gpu, size, size_name)
            encoder = self.gpu.device.create_command_encoder(label="offscreen")
            views, depth = frame.views()
            self.encode(encoder, views, depth, OFFSCREEN_FORMATS, draw, camera or self.scene.camera, size,
                        "albedo" if mode == "albedo" else "color")
            self.gpu.device.queue.submit([encoder.finish()])
            return frame.read(draw.technique.layer_range(draw.values))
