"""core.pass_timing: passes timed side by side, by timestamps or by wall clock net of an empty pass."""

from __future__ import annotations

import pytest
import wgpu

from wgpuviewer.core.pass_timing import time_passes

pytestmark = pytest.mark.requires_gpu

KERNEL = """
@group(0) @binding(0) var<storage, read_write> data: array<f32>;
@compute @workgroup_size(64)
fn main(@builtin(global_invocation_id) gid: vec3u) {
    var x = data[gid.x];
    for (var i = 0u; i < 256u; i++) { x = x * 0.999 + 0.5; }
    data[gid.x] = x;
}
"""


def _recorder(device, groups: int):
    pipeline = device.create_compute_pipeline(layout="auto", compute={
        "module": device.create_shader_module(code=KERNEL), "entry_point": "main"})
    buffer = device.create_buffer(size=groups * 64 * 4, usage=wgpu.BufferUsage.STORAGE)
    group = device.create_bind_group(layout=pipeline.get_bind_group_layout(0),
                                     entries=[{"binding": 0, "resource": {"buffer": buffer}}])

    def record(encoder, timestamp_writes=None):
        compute = encoder.begin_compute_pass(timestamp_writes=timestamp_writes)
        compute.set_pipeline(pipeline)
        compute.set_bind_group(0, group)
        compute.dispatch_workgroups(groups)
        compute.end()

    return record


@pytest.mark.parametrize("timestamps", [True, False])
def test_more_work_takes_longer_in_both_timers(gpu, timestamps):
    if timestamps and "timestamp-query" not in gpu.features:
        pytest.skip("the adapter has no timestamp-query")
    if timestamps and gpu.software:
        pytest.skip("lavapipe's compute timestamps are unreliable once the device has drawn (core/pass_timing.py)")
    small, large = _recorder(gpu.device, 16), _recorder(gpu.device, 4096)
    t = time_passes(gpu.device, [small, large], 5, timestamps=timestamps)
    assert t.timer == ("timestamp" if timestamps else "wall-net")
    assert all(s.shape == (5,) and (s >= 0).all() for s in t.samples_ms)
    assert t.median_ms[1] > t.median_ms[0]
    if not timestamps:
        assert t.overhead_ms > 0


def test_repeats_must_be_positive(gpu):
    with pytest.raises(ValueError, match="repeats"):
        time_passes(gpu.device, [], 0)
