"""Drawing a scene with one technique, into a window surface or offscreen.

Everything is built lazily from what the selected technique needs ("model only what a scene needs"):
a material's depth texture exists only once a technique that traces depth is drawn, pipelines are
compiled on first use and cached. ``Renderer.created`` logs each GPU resource it builds, so tests
(and curious users) can see exactly what a scene cost.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
import wgpu
from maptools.cache import cached_generate

from . import camera as cam
from . import meshes, textures
from .gpu import Gpu, create_texture, mip_chain
from .maps import MAP_SLOTS, layout_entries
from .scene import Camera, Scene
from .shaders import compose, pack_trace_params, trace_params_size
from .techniques import Technique, get_technique

MAX_LIGHTS = 4  # mirrors render.wgsl
COLOR_FORMAT = "rgba8unorm-srgb"  # offscreen colour: shaders write linear, PNGs get sRGB bytes
DATA_FORMAT = "rgba32uint"  # offscreen raw trace data (float bits): hit u, v, depth, fetches
LAYERS_FORMAT = "r32uint"  # offscreen: depth layers the search used per pixel
DEPTH_FORMAT = "depth32float"
FRAME_SIZE = 64 + 16 + 16 + MAX_LIGHTS * 32

#: Frame.mode values (render.wgsl).
MODES = {"color": 0, "cost": 1, "uv": 2, "depth": 3, "layers": 4}

_TEXTURE_BINDINGS = {"albedo": 2, "normal": 3}  # height-derived ones: maps.MAP_SLOTS
_TEXTURE_FORMATS = {"albedo": "rgba16float", "normal": "rgba8unorm"}


def _binding(texture_name: str) -> int:
    return MAP_SLOTS[texture_name].binding if texture_name in MAP_SLOTS else _TEXTURE_BINDINGS[texture_name]


@dataclass
class OffscreenImage:
    color: np.ndarray  # (H, W, 4) uint8, sRGB; alpha 0 where nothing was drawn
    data: np.ndarray  # (H, W, 4) float32: hit u, hit v, hit depth, fetches (negative: capped)
    layers: np.ndarray | None = None  # (H, W) uint32: depth layers the search used (0: no layers)
    layer_range: tuple[float, float] = (0.0, 1.0)  # the layers mode's grey: (N - lo) / (hi - lo)

    @property
    def covered(self) -> np.ndarray:
        return self.color[:, :, 3] > 0


class Renderer:
    def __init__(self, scene: Scene, gpu: Gpu):
        self.scene = scene
        self.gpu = gpu
        self.created: list[str] = []  # GPU resources built, in order: "kind:name"
        #: Runtime parameter overrides per technique (the viewer edits these).
        self.params = {name: dict(values) for name, values in scene.technique_params.items()}
        self._textures: dict[tuple[str, str], wgpu.GPUTexture] = {}
        self._pipelines: dict[tuple, wgpu.GPURenderPipeline] = {}
        self._material_groups: dict[tuple[str, str], tuple[wgpu.GPUBindGroup, wgpu.GPUBuffer]] = {}
        self._material_layouts: dict[tuple[str, ...], wgpu.GPUBindGroupLayout] = {}
        device = gpu.device
        U = wgpu.BufferUsage
        V, F = wgpu.ShaderStage.VERTEX, wgpu.ShaderStage.FRAGMENT
        self._frame_buffer = device.create_buffer(label="frame", size=FRAME_SIZE, usage=U.UNIFORM | U.COPY_DST)
        self._frame_layout = device.create_bind_group_layout(
            label="frame", entries=[{"binding": 0, "visibility": V | F, "buffer": {"type": "uniform"}}]
        )
        self._frame_group = device.create_bind_group(
            layout=self._frame_layout, entries=[{"binding": 0, "resource": {"buffer": self._frame_buffer}}]
        )
        self._object_layout = device.create_bind_group_layout(
            label="object", entries=[{"binding": 0, "visibility": V | F, "buffer": {"type": "uniform"}}]
        )
        self._sampler = device.create_sampler(
            label="material", address_mode_u="repeat", address_mode_v="repeat",
            mag_filter="linear", min_filter="linear", mipmap_filter="linear", max_anisotropy=1,
        )
        self._objects = [self._build_object(i, obj) for i, obj in enumerate(scene.objects)]

    # --- scene geometry (every technique needs it) -------------------------------------------

    def _build_object(self, index: int, obj):
        device = self.gpu.device
        vertices = meshes.build(obj.kind, obj.size)
        vbuf = device.create_buffer_with_data(label=f"mesh:{index}", data=vertices, usage=wgpu.BufferUsage.VERTEX)
        model = cam.translation(obj.position) @ cam.rotation_xyz(obj.rotation)
        normal_matrix = np.eye(4)
        normal_matrix[:3, :3] = np.linalg.inv(model[:3, :3]).T
        uv_scale = self.scene.materials[obj.material].uv_scale
        data = np.concatenate([cam.to_wgsl(model).ravel(), cam.to_wgsl(normal_matrix).ravel(), [*uv_scale, 0, 0]])
        ubuf = device.create_buffer_with_data(
            label=f"object:{index}", data=data.astype(np.float32), usage=wgpu.BufferUsage.UNIFORM
        )
        group = device.create_bind_group(layout=self._object_layout, entries=[{"binding": 0, "resource": {"buffer": ubuf}}])
        return obj.material, vbuf, len(vertices), group

    # --- lazily built material resources -----------------------------------------------------

    def _texture(self, material_name: str, kind: str) -> wgpu.GPUTexture:
        key = (material_name, kind)
        if key not in self._textures:
            material = self.scene.materials[material_name]
            label = f"{material_name}.{kind}"
            if kind in MAP_SLOTS:
                slot = MAP_SLOTS[kind]
                self._textures[key] = slot.build(self.gpu, self._depth_data(material), material.height_scale, label)
            else:
                if kind == "normal":
                    data = self._normal_data(material) * 0.5 + 0.5
                else:
                    data = textures.load_albedo(material.albedo)
                self._textures[key] = create_texture(self.gpu, mip_chain(data), _TEXTURE_FORMATS[kind], label)
            self.created.append(f"texture:{label}")
        return self._textures[key]

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
        return cached_generate("normal", height, backend="cpu", strength=strength, y="directx")

    def _material_layout(self, technique: Technique) -> wgpu.GPUBindGroupLayout:
        if technique.textures not in self._material_layouts:
            F = wgpu.ShaderStage.FRAGMENT
            entries = [
                {"binding": 0, "visibility": F, "buffer": {"type": "uniform"}},
                {"binding": 1, "visibility": F, "sampler": {"type": "filtering"}},
            ] + [
                {"binding": _TEXTURE_BINDINGS[t], "visibility": F, "texture": {"sample_type": "float"}}
                for t in technique.textures if t in _TEXTURE_BINDINGS
            ] + layout_entries(technique.textures, F)
            self._material_layouts[technique.textures] = self.gpu.device.create_bind_group_layout(
                label="material:" + "+".join(technique.textures), entries=entries
            )
        return self._material_layouts[technique.textures]

    def _material_group(self, material_name: str, technique: Technique):
        key = (material_name, technique.name)
        if key not in self._material_groups:
            device = self.gpu.device
            params = device.create_buffer(
                label=f"params:{material_name}:{technique.name}",
                size=trace_params_size(),
                usage=wgpu.BufferUsage.UNIFORM | wgpu.BufferUsage.COPY_DST,
            )
            entries = [{"binding": 0, "resource": {"buffer": params}}, {"binding": 1, "resource": self._sampler}]
            entries += [
                {"binding": _binding(t), "resource": self._texture(material_name, t).create_view()}
                for t in technique.textures
            ]
            group = device.create_bind_group(layout=self._material_layout(technique), entries=entries)
            self._material_groups[key] = (group, params)
        return self._material_groups[key]

    def pipeline(self, technique: Technique, formats: tuple[str, ...]) -> wgpu.GPURenderPipeline:
        key = (technique.name, formats)
        if key not in self._pipelines:
            device = self.gpu.device
            label = f"render:{technique.name}:{'+'.join(formats)}"
            module = device.create_shader_module(label=label, code=compose(technique, "render"))
            layout = device.create_pipeline_layout(
                label=label,
                bind_group_layouts=[self._frame_layout, self._material_layout(technique), self._object_layout],
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
                depth_stencil={"format": DEPTH_FORMAT, "depth_write_enabled": True, "depth_compare": "less"},
                fragment={
                    "module": module,
                    "entry_point": "fs_color" if len(formats) == 1 else "fs_data",
                    "targets": [{"format": f} for f in formats],
                },
            )
            self.created.append(f"pipeline:{technique.name}:{'+'.join(formats)}")
        return self._pipelines[key]

    # --- frames ------------------------------------------------------------------------------

    def _write_frame(self, camera: Camera, size: tuple[int, int], mode: str, cost_scale: float):
        w, h = size
        view_proj = cam.perspective(camera.fov, w / h, camera.near, camera.far) @ cam.look_at(
            camera.position, camera.target, camera.up
        )
        lights = np.zeros((MAX_LIGHTS, 8), np.float32)
        for i, light in enumerate(self.scene.lights[:MAX_LIGHTS]):
            if light.kind == "directional":
                lights[i, :4] = [*(-np.asarray(light.direction)), 0.0]  # towards the light
            else:
                lights[i, :4] = [*light.position, 1.0]
            lights[i, 4:7] = np.asarray(light.color) * light.intensity
        header = np.zeros(8, np.float32)
        header[:3] = camera.position
        counts = np.array([min(len(self.scene.lights), MAX_LIGHTS), MODES[mode]], np.uint32)
        data = b"".join(
            [
                cam.to_wgsl(view_proj).tobytes(),
                header[:4].tobytes(),
                counts.tobytes(),
                np.array([cost_scale, 0.0], np.float32).tobytes(),
                lights.tobytes(),
            ]
        )
        self.gpu.device.queue.write_buffer(self._frame_buffer, 0, data)

    def encode(
        self,
        encoder: wgpu.GPUCommandEncoder,
        color_views: list,
        depth_view,
        formats: tuple[str, ...],
        technique_name: str,
        camera: Camera,
        size: tuple[int, int],
        mode: str = "color",
        *,
        clear: bool = True,
        scissor: tuple[int, int, int, int] | None = None,
        timestamp_writes: dict | None = None,
    ) -> None:
        """Record one frame of ``technique_name`` into ``color_views`` (1 target: fs_color; 3: fs_data, formats
        (COLOR_FORMAT, DATA_FORMAT, LAYERS_FORMAT)).

        ``clear=False`` keeps what the targets hold and ``scissor`` (x, y, w, h) limits the drawing:
        together they put several techniques side by side in one frame. ``timestamp_writes`` goes to
        the render pass as is (GPU timing).
        """
        technique = get_technique(technique_name)
        params = self.params.get(technique.name) or technique.defaults()
        self._write_frame(camera, size, mode, technique.cost_scale(params))
        pipeline = self.pipeline(technique, formats)
        groups = {}
        for material_name in {m for m, *_ in self._objects}:
            group, params_buffer = self._material_group(material_name, technique)
            material = self.scene.materials[material_name]
            depth_shape = self._texture(material_name, "depth").size[1::-1] if technique.needs_depth else (1, 1)
            self.gpu.device.queue.write_buffer(
                params_buffer, 0, pack_trace_params(material.height_scale, depth_shape, technique.trace_values(params))
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
                "view": depth_view, "depth_load_op": "clear", "depth_store_op": "discard", "depth_clear_value": 1.0,
            },
            timestamp_writes=timestamp_writes,
        )
        if scissor is not None:
            rpass.set_scissor_rect(*scissor)
        rpass.set_pipeline(pipeline)
        rpass.set_bind_group(0, self._frame_group)
        for material_name, vbuf, count, object_group in self._objects:
            rpass.set_bind_group(1, groups[material_name])
            rpass.set_bind_group(2, object_group)
            rpass.set_vertex_buffer(0, vbuf)
            rpass.draw(count)
        rpass.end()

    def render(self, technique_name: str, size: tuple[int, int], camera: Camera | None = None) -> OffscreenImage:
        """Draw offscreen and read back both the colour and the raw trace data."""
        device = self.gpu.device
        w, h = size
        usage = wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC
        color = device.create_texture(label="offscreen:color", size=(w, h, 1), format=COLOR_FORMAT, usage=usage)
        data = device.create_texture(label="offscreen:data", size=(w, h, 1), format=DATA_FORMAT, usage=usage)
        layers = device.create_texture(label="offscreen:layers", size=(w, h, 1), format=LAYERS_FORMAT, usage=usage)
        depth = device.create_texture(
            label="offscreen:depth", size=(w, h, 1), format=DEPTH_FORMAT, usage=wgpu.TextureUsage.RENDER_ATTACHMENT
        )
        encoder = device.create_command_encoder(label="offscreen")
        self.encode(
            encoder, [color.create_view(), data.create_view(), layers.create_view()], depth.create_view(),
            (COLOR_FORMAT, DATA_FORMAT, LAYERS_FORMAT), technique_name, camera or self.scene.camera, size,
        )
        device.queue.submit([encoder.finish()])
        technique = get_technique(technique_name)
        return OffscreenImage(
            color=_read_texture(device, color, 4, np.uint8),
            data=_read_texture(device, data, 4, np.uint32).view(np.float32),
            layers=_read_texture(device, layers, 1, np.uint32)[:, :, 0],
            layer_range=layer_range(self.params.get(technique.name) or technique.defaults()),
        )


def layer_range(params: dict) -> tuple[float, float]:
    """(lo, hi) of the layers mode's grey (N - lo) / (hi - lo); mirrors layer_grey in render.wgsl."""
    if params.get("max_layers", 0) > 0:
        return float(params.get("min_layers", 0)), float(params["max_layers"])
    return 0.0, float(max(params.get("layers", 0), params.get("linear_steps", 0), 1))


def _read_texture(device, texture, channels: int, dtype) -> np.ndarray:
    w, h = texture.size[:2]
    row = w * channels * np.dtype(dtype).itemsize
    raw = device.queue.read_texture(
        {"texture": texture, "mip_level": 0, "origin": (0, 0, 0)},
        {"offset": 0, "bytes_per_row": row, "rows_per_image": h},
        (w, h, 1),
    )
    return np.frombuffer(raw, dtype).reshape(h, w, channels).copy()
