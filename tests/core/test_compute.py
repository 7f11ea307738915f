"""The compute-kernel helper: a round trip through a tiny kernel, compile errors at the original file:line, limit
refusals before any GPU work, one Compute (and one compiled kernel per source) per device."""

from __future__ import annotations

import threading

import numpy as np
import pytest
import wgpu

from wgpuviewer.core.compute import Compute, KernelError, LimitError, compute_for, source_hash, workgroups
from wgpuviewer.core.gpu import Gpu
from wgpuviewer.core.wgsl import Generated, compose

SCALE = """@group(0) @binding(0) var<storage, read> src: array<f32>;
@group(0) @binding(1) var<storage, read_write> dst: array<f32>;

@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) id: vec3u) {
    if (id.x < arrayLength(&src)) {
        dst[id.x] = src[id.x] * FACTOR;
    }
}
"""
FIX = "use the CPU path"


def factor(value: float) -> Generated:
    return Generated("<generated: factor>", f"const FACTOR: f32 = {value};\n")


@pytest.fixture
def scale_wgsl(tmp_path):
    path = tmp_path / "scale.wgsl"
    path.write_text(SCALE)
    return str(path)


def test_workgroups_cover_the_threads():
    assert workgroups((100,), (64,)) == (2, 1, 1)
    assert workgroups((17, 8, 3), (8, 8, 1)) == (3, 1, 3)


def test_source_hash_is_the_composed_code(scale_wgsl):
    assert source_hash(compose(factor(3.0), scale_wgsl)) == source_hash(compose(factor(3.0), scale_wgsl))
    assert source_hash(compose(factor(3.0), scale_wgsl)) != source_hash(compose(factor(2.0), scale_wgsl))


@pytest.mark.requires_gpu
def test_a_kernel_round_trip(gpu, scale_wgsl):
    c = compute_for(gpu)
    kernel = c.kernel(factor(3.0), scale_wgsl, label="test scale", fix=FIX)
    assert kernel.source_hash == source_hash(compose(factor(3.0), scale_wgsl))
    data = np.arange(100, dtype=np.float32)  # two workgroups, the second one partly outside the data
    with c.guard("test scale", FIX):
        src = c.storage(data, "test src", FIX)
        dst = c.storage(data.nbytes, "test dst", FIX)
        encoder = c.encoder("test scale")
        kernel.dispatch(encoder, "main", {0: src, 1: dst}, threads=(len(data),), size=(64,))
        c.submit(encoder)
        assert np.array_equal(c.read(dst, len(data)), data * 3)


@pytest.mark.requires_gpu
def test_a_compile_error_is_located_in_its_file(gpu, tmp_path):
    path = tmp_path / "broken.wgsl"
    path.write_text(SCALE.replace("src[id.x] * FACTOR", "src[id.x] * undefined_name"))
    kernel = compute_for(gpu).kernel(factor(1.0), str(path), label="test broken", fix=FIX)
    with pytest.raises(KernelError) as error:
        kernel.pipeline("main")
    message = str(error.value)
    line = SCALE.splitlines().index("        dst[id.x] = src[id.x] * FACTOR;") + 1
    assert f"{path}:{line}:" in message and "undefined_name" in message
    assert gpu.summary in message and message.endswith(FIX)


@pytest.mark.requires_gpu
def test_limits_are_refused_before_any_gpu_work(gpu, scale_wgsl):
    c = compute_for(gpu)
    with pytest.raises(LimitError, match=f"a test volume needs a {c.max_buffer + 1}-byte buffer.*; {FIX}"):
        c.storage(c.max_buffer + 1, "a test volume", FIX)
    kernel = c.kernel(factor(1.0), scale_wgsl, label="test scale", fix=FIX)
    limit = gpu.device.limits["max-compute-workgroups-per-dimension"]
    src = c.storage(4, "test src", FIX)
    with pytest.raises(LimitError, match=f"test scale:main: {limit + 1} workgroups along x, more than the {limit}"):
        kernel.dispatch(c.encoder("test"), "main", {0: src, 1: src}, threads=(64 * limit + 1,), size=(64,))


@pytest.mark.requires_gpu
def test_one_compute_and_one_kernel_per_source_per_device(gpu, scale_wgsl):
    c = compute_for(gpu)
    assert compute_for(gpu) is c and gpu.cache["compute"] is c
    kernel = c.kernel(factor(1.0), scale_wgsl, label="test scale", fix=FIX)
    assert c.kernel(factor(1.0), scale_wgsl, label="test scale", fix=FIX) is kernel
    assert c.kernel(factor(2.0), scale_wgsl, label="test scale", fix=FIX) is not kernel
    assert c.kernel_of(compose(factor(1.0), scale_wgsl), label="test scale", fix=FIX) is kernel  # same source
    entries = [[{"binding": 0, "visibility": wgpu.ShaderStage.COMPUTE,
                 "buffer": {"type": wgpu.BufferBindingType.storage}}]]
    assert c.layout(entries, "test") is c.layout(entries, "test")
    other = Gpu(gpu.adapter, gpu.device, gpu.features)  # a second Gpu: its own cache and lock
    found: list[Compute] = []
    threads = [threading.Thread(target=lambda: found.append(compute_for(other))) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert len({id(f) for f in found}) == 1 and found[0] is not c and found[0].lock is other.lock
