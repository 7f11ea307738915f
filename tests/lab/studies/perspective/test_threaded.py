"""The paper's parallel forms on real threads: the threaded loops (a span's lanes or ends on threads, spans on
threads) write the scalar build's uv and flags bit for bit at 2 threads, the timing gives one row per method,
placement and thread count with ratios to the scalar ``direct`` of the same round, and the report names them."""

from __future__ import annotations

import pytest

from wgpuviewer.lab.studies.perspective import threaded, threads_report
from wgpuviewer.lab.studies.perspective.geometry import Setup, build
from wgpuviewer.lab.studies.perspective.run import configured

pytest.importorskip("numba")


@pytest.fixture(scope="module")
def quad():
    return build(configured(Setup(span_length=96, rows=6, tilt=80.0)))


@pytest.fixture(scope="module")
def rows(quad):
    return threaded.measure(quad.coefficients, quad.spans, 2, 0.0005, methods=("direct", "parallel_4"))


def test_threaded_loops_write_the_scalar_builds_result_bit_for_bit(quad, rows):
    threaded_build = threaded.threaded_build()
    threaded_module = threaded.numba_module()
    threaded_module.set_num_threads(min(2, threaded_module.config.NUMBA_NUM_THREADS))
    for name, placement in (("parallel_4", "lanes"), ("two_ended", "lanes"), ("parallel_4", "spans")):
        assert threaded.check(threaded_build, name, placement, quad.coefficients, quad.spans), (name, placement)
    assert all(r["identical"] for r in rows)


def test_only_the_parallel_forms_put_lanes_on_threads():
    with pytest.raises(ValueError, match="only the parallel forms"):
        threaded.ThreadedBuild().loop("direct", "lanes")


def test_every_configuration_is_timed_once_against_the_scalar_direct(rows):
    counts = threaded.thread_counts()
    keys = [(r["method"], r["placement"], r["threads"]) for r in rows]
    assert len(keys) == len(set(keys)) == 4 + len(counts) * (2 + 1)
    assert 1 in counts and max(counts) == threaded.numba_module().config.NUMBA_NUM_THREADS
    base = next(r for r in rows if (r["method"], r["placement"]) == ("direct", "scalar"))
    assert base["ratio_scalar_direct"] == 1.0 and base["speedup"] == 1.0
    assert all(r["ns_per_texel"] > 0 and r["cores"] >= 1 and r["span_length"] == 96 for r in rows)


def test_the_section_names_the_cores_and_every_placement(rows):
    text = "\n".join(threads_report.section(rows))
    assert f"{rows[0]['cores']} logical CPUs" in text
    assert "| `parallel_4` |" in text and "| lanes |" in text and "| spans |" in text
    assert threads_report.section([]) == ["Not timed in this suite (the full suite and `--threads-only` time it)."]
