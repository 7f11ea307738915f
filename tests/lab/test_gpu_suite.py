"""``./dev gpu-suite`` (wgpuviewer.lab.gpusuite): the adapter check, the time boxes, a stopped part's record and kept
rows, the manifest, and the README's headline generated from the newest run (a real GPU's first, else a software
adapter's named as such) by ``wgpuviewer docs``, never by a run; a tiny run end to end on the test adapter, with one
part stopped at its time box."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from wgpuviewer.lab import docs, gpusuite
from wgpuviewer.lab.bench import run as bench
from wgpuviewer.relief.renderer import Renderer  # noqa: F401 - imports wgpu before the log fixture touches its logger

ROOT = Path(__file__).resolve().parents[2]
H200 = "NVIDIA H200 (DiscreteGPU) via Vulkan"
LLVMPIPE = "llvmpipe (LLVM 15.0.6, 256 bits) (CPU) via Vulkan"


HEADLINE_BEGIN = docs.BEGIN.format(name="headline")


def headline_section(text: str) -> str:
    return text.split(HEADLINE_BEGIN, 1)[1].split(docs.END, 1)[0].strip()


def headline_block(root: Path) -> str:
    """What `wgpuviewer docs` writes there: the headline, after its run's stale label when it is not fresh."""
    block = next(b for b in docs.BLOCKS if (b.page, b.name) == ("README.md", "headline"))
    return docs.body(block, root).strip()


def test_the_readme_headline_is_generated_from_the_committed_runs():
    """Regenerate it with `wgpuviewer docs`."""
    text = (ROOT / "README.md").read_text(encoding="utf-8")
    assert text.count(HEADLINE_BEGIN) == 1
    assert headline_section(text) == headline_block(ROOT)
    assert gpusuite.headline_markdown(ROOT / "benchmarks", ROOT).strip() in headline_section(text)


@pytest.mark.parametrize("device, slug", [("NVIDIA H200", "nvidia-h200"), ("NVIDIA H100 80GB HBM3", "nvidia-h100-80gb-hbm3"),
                                          ("llvmpipe (LLVM 15.0.6, 256 bits)", "llvmpipe"), ("(?)", "adapter")])
def test_adapter_folder_names(device, slug):
    assert gpusuite.adapter_slug(device) == slug


def test_time_boxes_share_what_the_budget_leaves():
    plan = gpusuite.Plan(gpusuite.PARTS, 480.0, {})
    assert plan.box("bench", 450.0) == pytest.approx(270.0)
    assert plan.box("filtering", 100.0) == pytest.approx(50.0)  # what bench left, shared with perspective
    assert plan.box("perspective", 30.0) == pytest.approx(30.0)
    fixed = gpusuite.Plan(gpusuite.PARTS, 480.0, {"perspective": 50.0})
    assert fixed.box("bench", 450.0) == pytest.approx(400.0 * 0.6 / 0.8)  # the fixed box is kept for its part
    assert fixed.box("perspective", 20.0) == 20.0  # never past the budget


def test_a_parts_output_keeps_its_lines_and_its_last_progress():
    output = gpusuite.PartOutput()
    output.take(b"note: --frames 2: noisy")
    output.take("bench:  50%|█████     | 4/8 [00:01<00:01, 3.0row/s]".encode())
    output.take("bench:  75%|███████▌  | 6/8 [00:02<00:00, 3.0row/s]".encode())
    assert output.lines == ["note: --frames 2: noisy"]
    record = {"status": "stopped", "box_s": 30.0, "progress": output.progress, "rows": 6}
    assert gpusuite.describe(record) == "stopped at its 30 s time box after 6 of 8 steps; 6 rows kept"


@pytest.mark.parametrize("argv, names", [
    (["--parts", "bench,timing"], "--parts"), (["--box", "bench=0"], "--box"), (["--box", "perspective=5",
                                                                                 "--parts", "bench"], "--box"),
    (["--budget", "10"], "--budget")])
def test_bad_options_are_one_line_errors(argv, names, capsys):
    assert gpusuite.main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert err.startswith("gpu-suite: error:") and names in err and "\n" not in err


# --- the headline from fixture runs ----------------------------------------------------------------------------

def bench_row(adapter: str, technique: str, params: str, angle: float, p95: float, ratio: float, simd: float) -> dict:
    row = {**bench.TABLE.blank(), "suite": "full", "heightmap": "bricks", "heightmap_size": "256x256",
           "technique": technique, "params": params, "angle": angle, "angle_min": angle - 0.5,
           "angle_max": angle + 0.5, "resolution": "1920x1080", "adapter": adapter, "backend": "Vulkan",
           "timer": "timestamp", "frames": 20, "gpu_ms": 0.5 * ratio, "basic_ms": 0.5, "ratio_to_basic": ratio,
           "fetches_mean": simd * 0.8, "fetches_p95": simd, "uv_err_mean": p95 / 2, "uv_err_p95": p95,
           "uv_err_max": p95 * 2, "psnr_db": 40.0, "capped_fraction": 0.0, "covered_fraction": 1.0,
           "eval_pixels": 100, "fetches_simd": simd, "simd_tile": "8x4", "map_bytes": 1024}
    return row


def fixture_run(out_root: Path, name: str, adapter: str, software: bool, started: str, suite: str = "full") -> Path:
    """A gpu-suite run folder as the command writes it: bench's results (pom 16 within 0.5 texel, distance 256
    within 0.25), filtering finished with a report, perspective stopped at its box."""
    folder = out_root / name
    (folder / "bench").mkdir(parents=True)
    (folder / "filtering").mkdir()
    rows = [bench_row(adapter, technique, params, angle, p95, ratio, simd)
            for angle in (0.0, 60.0)
            for technique, params, p95, ratio, simd in (("basic", "-", 0.0 if angle == 0 else 9.0, 1.0, 0.0),
                                                        ("pom", "layers=16", 0.3, 2.0, 17.0),
                                                        ("distance", "iterations=256", 0.1, 4.0, 20.0))]
    bench.TABLE.write(folder / "bench" / "results.csv", rows)
    (folder / "bench" / "report.md").write_text("# bench\n")
    (folder / "filtering" / "report.md").write_text("# filtering\n")
    parts = [{"name": "bench", "folder": "bench", "status": "finished", "detail": "finished in 300 s, 6 rows"},
             {"name": "filtering", "folder": "filtering", "status": "finished", "detail": "finished in 90 s, 9 rows"},
             {"name": "perspective", "folder": "perspective", "status": "stopped",
              "detail": "stopped at its 60 s time box; 0 rows kept"}]
    manifest = {"command": "./dev gpu-suite", "suite": suite, "adapter": adapter, "software": software,
                "started": started, "seconds": 470.0, "budget_s": 480.0, "parts": parts}
    (folder / gpusuite.MANIFEST).write_text(json.dumps(manifest))
    return folder


def test_the_headline_comes_from_the_newest_real_gpu_run(tmp_path):
    runs = tmp_path / "benchmarks"
    fixture_run(runs, "nvidia-h100", H200.replace("H200", "H100"), False, "2026-11-01T10:00:00Z")
    fixture_run(runs, "nvidia-h200", H200, False, "2026-12-01T10:00:00Z")
    fixture_run(runs, "llvmpipe", LLVMPIPE, True, "2026-12-05T10:00:00Z")  # newer, but no GPU
    text = gpusuite.headline_markdown(runs, tmp_path)
    assert f"**{H200}** (a GPU), 2026-12-01 10:00 UTC" in text
    assert "[report](benchmarks/nvidia-h200/bench/report.md)" in text
    assert "filtering ([report](benchmarks/nvidia-h200/filtering/report.md)): finished in 90 s" in text
    assert "perspective: stopped at its 60 s time box" in text
    lines = text.splitlines()
    assert "| ≤ 0.25 texel | `distance` iterations=256 | 4.00 | 2.000 | 20.0 | itself |" in lines
    assert "| ≤ 0.5 texel | `pom` layers=16 | 2.00 | 1.000 | 17.0 | 0.850× its SIMD-tile fetches, 0.50× its time |" \
        in lines
    assert "4 of the 132 SMs run fragment shaders" in text  # beside the H200's milliseconds
    for link in ("benchmarks/nvidia-h200/manifest.json", "benchmarks/nvidia-h200/bench/report.md"):
        assert (tmp_path / link).is_file()


def test_without_a_gpu_run_the_headline_names_the_software_adapter(tmp_path):
    runs = tmp_path / "benchmarks"
    assert gpusuite.headline_markdown(runs, tmp_path).startswith("No `./dev gpu-suite` run")
    fixture_run(runs, "llvmpipe-smoke", LLVMPIPE, True, "2026-12-01T10:00:00Z")
    fixture_run(runs, "llvmpipe", LLVMPIPE, True, "2026-12-02T10:00:00Z")
    text = gpusuite.headline_markdown(runs, tmp_path)
    assert f"**{LLVMPIPE}** (a software adapter, not a GPU), 2026-12-02" in text
    assert f"**{LLVMPIPE} is a software adapter**" in text and "No real-GPU run" in text
    assert "SMs" not in text


def test_the_headline_shows_the_widest_run_before_a_newer_smaller_one(tmp_path):
    runs = tmp_path / "benchmarks"
    fixture_run(runs, "llvmpipe-reduced", LLVMPIPE, True, "2026-12-01T10:00:00Z", suite="reduced")
    fixture_run(runs, "llvmpipe-smoke", LLVMPIPE, True, "2026-12-02T10:00:00Z", suite="smoke")
    assert gpusuite.headline_run(gpusuite.load_runs(runs)).folder.name == "llvmpipe-reduced"
    manifest = runs / "llvmpipe-reduced" / gpusuite.MANIFEST
    stopped = json.loads(manifest.read_text())
    stopped["parts"][0]["status"] = "stopped"
    manifest.write_text(json.dumps(stopped))
    assert gpusuite.headline_run(gpusuite.load_runs(runs)).folder.name == "llvmpipe-smoke"  # a finished bench first
    fixture_run(runs, "nvidia-h200-smoke", H200, False, "2026-11-01T10:00:00Z", suite="smoke")
    assert gpusuite.headline_run(gpusuite.load_runs(runs)).folder.name == "nvidia-h200-smoke"  # a GPU first


def test_the_docs_command_rewrites_only_the_headline_from_a_new_run(tmp_path, capsys):
    runs = tmp_path / "benchmarks"
    fixture_run(runs, "nvidia-h200", H200, False, "2026-12-01T10:00:00Z")
    readme = tmp_path / "README.md"
    shutil.copy(ROOT / "README.md", readme)
    before = readme.read_text(encoding="utf-8")
    assert docs.run(tmp_path, check=True) == 1  # the page is not the new run's yet: named, nothing written
    assert "README.md: block 'headline' differs" in capsys.readouterr().out
    assert readme.read_text(encoding="utf-8") == before
    assert docs.run(tmp_path, check=False) == 0
    assert capsys.readouterr().out.splitlines() == ["README.md: block 'headline' regenerated from the widest "
                                                    "./dev gpu-suite run under benchmarks/"]
    after = readme.read_text(encoding="utf-8")
    assert headline_section(after).endswith(gpusuite.headline_markdown(runs, tmp_path))
    assert "`benchmarks/nvidia-h200/bench/` has no stamp.json" in headline_section(after)  # the fixture has none
    assert after.split(HEADLINE_BEGIN)[0] == before.split(HEADLINE_BEGIN)[0]
    assert after.split(HEADLINE_BEGIN)[1].split(docs.END, 1)[1] == before.split(HEADLINE_BEGIN)[1].split(docs.END, 1)[1]
    assert docs.run(tmp_path, check=True) == 0


def test_a_stopped_bench_gets_its_report_from_the_views_it_finished(tmp_path):
    folder = fixture_run(tmp_path, "run", H200, False, "2026-12-01T10:00:00Z") / "bench"
    (folder / "report.md").unlink()
    note = gpusuite.report_kept_bench_rows(folder, "wgpuviewer bench --suite full --out bench")
    assert note == "report.md and plots made from the rows it kept"
    report = (folder / "report.md").read_text(encoding="utf-8")
    assert "pom layers=16" in report and "wgpuviewer bench --suite full" in report
    assert len(bench.TABLE.read(folder / "results.csv")) == 6


# --- a tiny run on the test adapter ------------------------------------------------------------------------------

@pytest.fixture(scope="module")
def tiny_run(tmp_path_factory, adapter):
    """`--suite tiny` with perspective's box far shorter than it takes: bench and filtering finish, perspective
    is stopped; into a temp output root."""
    root = tmp_path_factory.mktemp("gpu-suite")
    code = gpusuite.main(["--suite", "tiny", "--allow-software", "--box", "perspective=2", "--out-root",
                          str(root / "benchmarks")])
    folders = [p.parent for p in (root / "benchmarks").glob(f"*/{gpusuite.MANIFEST}")]
    assert len(folders) == 1
    return code, folders[0], root


@pytest.mark.requires_gpu
def test_a_software_adapter_is_refused_without_allow_software(adapter, tmp_path, capsys):
    if "(CPU)" not in adapter:
        pytest.skip(f"the test adapter {adapter} is not a software one")
    assert gpusuite.main(["--suite", "tiny", "--out-root", str(tmp_path / "runs")]) == 2
    err = capsys.readouterr().err
    assert "software adapter" in err and "--allow-software" in err
    assert not list((tmp_path / "runs").iterdir())


@pytest.mark.requires_gpu
def test_tiny_run_records_every_part_and_stops_the_one_past_its_box(tiny_run, adapter):
    code, folder, _ = tiny_run
    assert code == 1  # a part did not finish
    assert folder.name == gpusuite.adapter_slug(adapter.split(" (")[0]) + "-tiny"
    manifest = json.loads((folder / gpusuite.MANIFEST).read_text(encoding="utf-8"))
    assert manifest["adapter"] == adapter and manifest["suite"] == "tiny" and manifest["budget_s"] == 480.0
    assert manifest["started"].endswith("Z") and manifest["seconds"] > 0
    parts = {p["name"]: p for p in manifest["parts"]}
    assert list(parts) == list(gpusuite.PARTS)
    for name in ("bench", "filtering"):
        assert parts[name]["status"] == "finished", parts[name]
        assert parts[name]["rows"] > 0 and (folder / name / "report.md").is_file()
        assert parts[name]["command"].startswith(f"wgpuviewer {name} --suite smoke")
    assert bench.TABLE.read(folder / "bench" / "results.csv")[0]["adapter"] == adapter
    stopped = parts["perspective"]
    assert stopped["status"] == "stopped" and stopped["box_s"] == 2.0 and stopped["rows"] == 0
    assert stopped["seconds"] < 2.0 + gpusuite.STOP_GRACE_S + 5.0
    assert stopped["detail"].startswith("stopped at its 2 s time box")
    assert not list(folder.rglob(".*.tmp"))  # atomic writes: a stopped part leaves no temp file behind


@pytest.mark.requires_gpu
def test_the_headline_of_a_tiny_run_names_the_software_adapter(tiny_run, adapter):
    _, folder, root = tiny_run
    assert not (root / "README.md").exists()  # a run writes no page
    shutil.copy(ROOT / "README.md", root / "README.md")
    for code in ("wgpuviewer", "wgsl", "maptools"):  # the code the run measured: it is fresh, no stale label
        (root / code).symlink_to(ROOT / code)
    _, new, changed = docs.regenerate(root, root / "README.md")
    assert changed == ["headline"]
    section = headline_section(new)
    assert section == gpusuite.headline_markdown(folder.parent, root)
    assert f"**{adapter}**" in section and f"benchmarks/{folder.name}/bench/report.md" in section
    if "(CPU)" in adapter:
        assert "is a software adapter" in section
