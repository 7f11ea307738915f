"""The render pipelines and what they are laid out with: the bind-group layouts (group 0 the Frame, 1 a material's
trace parameters, sampler and textures, 2 the Object, ``FILTER_GROUP`` the filter's uniform and sampler), the
samplers, and the pipelines themselves, compiled on first use and cached per technique x filter x derivative
source x target formats x fragment entry x material variant (``shaders.MaterialVariant``: shadows, depth offset,
addressing and the technique's code paths the material runs, e.g. auto's methods). One ``Pipelines`` is
shared by renderers of scenes with the same materials (``Renderer(..., like=...)``)."""

from __future__ import annotations

import wgpu

from wgpuviewer import meshes
from wgpuviewer.core.gpu import Gpu
from wgpuviewer.techniques import Technique

from .filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER, sampler_descriptor
from .maps import PARAMS_BINDING, SAMPLER_BINDING, layout_entries
from .shaders import PLAIN, MaterialVariant, compose_technique
from .targets import DATA_OUT, DEPTH_FORMAT, hit_depth_outputs


def fragment_entry(formats: tuple[str, ...], mode: str, hit_depth: bool = False) -> str:
    """The fragment entry point of render.wgsl that draws into ``formats`` in ``mode``; ``hit_depth``: the one
    that also writes the traced hit's depth (depth_offset materials)."""
    entry = "fs_data" if len(formats) > 1 else "fs_view_depth" if mode == "depth" else "fs_color"
    return entry + "_hit_depth" if hit_depth else entry


def module(technique: Technique, filter: str = DEFAULT_FILTER, derivatives: str = DEFAULT_DERIVATIVES,
           variant: MaterialVariant = PLAIN):
    """The composed render module (``core.wgsl.Module``) of a technique with a filter, derivative source and
    material variant."""
    return compose_technique(technique, "render", filter, derivatives,
                             records=(DATA_OUT.generated(), hit_depth_outputs(DATA_OUT)), variant=variant)


class Pipelines:
    """Layouts, samplers and the pipeline cache of one device; ``created`` gets "pipeline:..." for each pipeline
    compiled (the renderer's log)."""

    def __init__(self, gpu: Gpu):
        self.gpu = gpu
        device = gpu.device
        V, F = wgpu.ShaderStage.VERTEX, wgpu.ShaderStage.FRAGMENT
        #: (technique name, filter, derivatives, formats, entry, variant) -> pipeline
        self.cache: dict[tuple, wgpu.GPURenderPipeline] = {}
        self._techniques: dict[str, Technique] = {}  # the technique of each name in the cache
        self._material_layouts: dict[tuple[str, ...], wgpu.GPUBindGroupLayout] = {}
        self.frame_layout = device.create_bind_group_layout(
            label="frame", entries=[{"binding": 0, "visibility": V | F, "buffer": {"type": "uniform"}}]
        )
        self.object_layout = device.create_bind_group_layout(
            label="object", entries=[{"binding": 0, "visibility": V | F, "buffer": {"type": "uniform"}}]
        )
        self.sampler = device.create_sampler(
            label="material", address_mode_u="repeat", address_mode_v="repeat",
            mag_filter="linear", min_filter="linear", mipmap_filter="linear", max_anisotropy=1,
        )
        # address = "clamp" materials: the uv square is the relief's extent
        self.clamp_sampler = device.create_sampler(
            label="material:clamp", address_mode_u="clamp-to-edge", address_mode_v="clamp-to-edge",
            mag_filter="linear", min_filter="linear", mipmap_filter="linear", max_anisotropy=1,
        )
        self.filter_layout = device.create_bind_group_layout(
            label="filter", entries=[{"binding": 0, "visibility": F, "buffer": {"type": "uniform"}},
                                     {"binding": 1, "visibility": F, "sampler": {"type": "filtering"}}]
        )
        self._filter_samplers: dict[tuple, wgpu.GPUSampler] = {}

    def material_layout(self, technique: Technique) -> wgpu.GPUBindGroupLayout:
        """Group 1's layout for the texture slots of ``technique``: its parameters, the sampler, the textures."""
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

    def filter_sampler(self, filter, values: dict) -> wgpu.GPUSampler:
        """The sampler a filter reads with at parameter ``values`` (one per distinct descriptor)."""
        descriptor = sampler_descriptor(filter, values)
        key = tuple(sorted(descriptor.items()))
        if key not in self._filter_samplers:
            self._filter_samplers[key] = self.gpu.device.create_sampler(label=f"filter:{filter.name}", **descriptor)
        return self._filter_samplers[key]

    def pipeline(self, technique: Technique, formats: tuple[str, ...], filter: str = DEFAULT_FILTER,
                 derivatives: str = DEFAULT_DERIVATIVES, mode: str = "color", variant: MaterialVariant = PLAIN,
                 created: list[str] | None = None) -> wgpu.GPURenderPipeline:
        """The render pipeline of a technique with a filter, derivative source and material variant into
        ``formats``: one target draws ``fs_color`` (``fs_view_depth`` for ``mode`` "depth"), more draw ``fs_data``
        (OFFSCREEN_FORMATS); a depth_offset variant draws their ``_hit_depth`` entry points."""
        entry = fragment_entry(formats, mode, variant.depth_offset)
        key = (technique.name, filter, derivatives, formats, entry, variant)
        if key not in self.cache:
            what = technique.name if (filter, derivatives) == (DEFAULT_FILTER, DEFAULT_DERIVATIVES) \
                else f"{technique.name}/{filter}/{derivatives}"
            what += variant.label
            self.cache[key] = self._compile(technique, filter, derivatives, variant, formats, entry,
                                            f"render:{what}:{entry}:{'+'.join(formats)}")
            self._techniques[technique.name] = technique
            if created is not None:
                depth_view = mode == "depth" and len(formats) == 1
                created.append(f"pipeline:{what}:{'+'.join(formats)}" + (":depth" if depth_view else ""))
        return self.cache[key]

    def _compile(self, technique: Technique, filter: str, derivatives: str, variant: MaterialVariant,
                 formats: tuple[str, ...], entry: str, label: str) -> wgpu.GPURenderPipeline:
        device = self.gpu.device
        code = module(technique, filter, derivatives, variant).code
        shader = device.create_shader_module(label=label, code=code)
        layout = device.create_pipeline_layout(
            label=label,
            bind_group_layouts=[self.frame_layout, self.material_layout(technique), self.object_layout,
                                self.filter_layout],
        )
        return device.create_render_pipeline(
            label=label,
            layout=layout,
            vertex={
                "module": shader,
                "entry_point": "vs_main",
                "buffers": [{"array_stride": meshes.VERTEX_STRIDE, "attributes": meshes.VERTEX_ATTRIBUTES}],
            },
            primitive={"topology": "triangle-list", "cull_mode": "back", "front_face": "ccw"},
            # Reversed Z (camera.perspective): 1 at near, 0 at far; the nearer surface has the greater depth.
            depth_stencil={"format": DEPTH_FORMAT, "depth_write_enabled": True, "depth_compare": "greater"},
            fragment={
                "module": shader,
                "entry_point": entry,
                "targets": [{"format": f} for f in formats],
            },
        )

    def rebuild(self, created: list[str] | None = None) -> list[tuple[Technique, str]]:
        """Compile every cached pipeline again from the WGSL files (hot reload; ``created`` as ``pipeline``'s). A
        pipeline that fails keeps its previous version; returns (technique, message) for each failure, the message
        located in the WGSL file (``file:line:column: reason``, core.wgsl.Module.locate)."""
        failures = []
        for key in list(self.cache):
            name, filter, derivatives, formats, entry, variant = key
            technique = self._techniques[name]
            old = self.cache.pop(key)
            try:
                self.pipeline(technique, formats, filter, derivatives,
                              "depth" if entry.startswith("fs_view_depth") else "color", variant, created)
            except wgpu.GPUError as error:
                self.cache[key] = old
                try:
                    message = module(technique, filter, derivatives, variant).locate(str(error))
                except OSError as read_error:
                    message = str(read_error)
                failures.append((technique, message))
            except OSError as error:  # a WGSL file vanished mid-edit
                self.cache[key] = old
                failures.append((technique, str(error)))
        return failures
