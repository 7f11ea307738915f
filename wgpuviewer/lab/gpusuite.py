"""``./dev gpu-suite`` (``python -m wgpuviewer.lab.gpusuite``): the measurements a GPU machine is lent for, in one
command within one time budget; and the README's headline from the newest run (``headline_markdown``), which
``wgpuviewer docs`` writes.

It checks the adapter first (a software adapter is refused unless ``--allow-software``), then runs
``wgpuviewer bench``, ``filtering`` and ``perspective`` (``--suite full``; ``reduced``, ``smoke`` and ``tiny`` are
smaller) one after the other as child processes, each within a time box cut from the budget (8 minutes: one device
call). A part that reaches its box gets SIGTERM, which it unwinds like Ctrl-C (no temp file left), and the run goes
on with the next part. Everything goes into ``benchmarks/<adapter>/`` (``<adapter>-<suite>`` for the smaller suites), one
folder per part, with ``manifest.json``: the adapter, the date, the budget, and per part its command, time box,
seconds, status (finished, stopped, failed, skipped), the rows it kept, its last progress line and its output.
bench writes its results view by view, so a stopped bench keeps the views it finished and its report is made from
them; the studies write theirs at the end, so a stopped study keeps nothing but its record in the manifest.

A run writes nothing outside its folder: the README's headline (between ``<!-- generated: headline -->`` and
``<!-- end generated -->``) is made from the bench results of the newest run under ``benchmarks/`` on a real GPU,
else of the newest run on a software adapter, which it names as such, by ``wgpuviewer docs`` (``wgpuviewer.lab.docs``),
which the run's last line asks for. Method: docs/benchmarks.md.

May import anything of the project, like ``cli``: it starts the measuring commands as child processes and reads
bench's results with bench's own table and headline rule.
"""

from __future__ import annotations

import contextlib
import csv
import datetime
import json
import math
import os
import re
import shutil
import signal
import subprocess
import sys
import threading
import time
from dataclasses import dataclass, field
from pathlib import Path

from wgpuviewer.core.commands import OneLineParser, add_backend_option, command_line, prepare_process, run_command
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import output_dir, write_bytes

PROG = "gpu-suite"
CHECKOUT = Path(__file__).resolve().parents[2]
#: The parts, in the order they run: the headline's measurement first, so that it gets its time box first.
PARTS = ("bench", "filtering", "perspective")
#: Each part's share of the time the budget leaves (a part that ends early leaves its rest to the next ones).
SHARES = {"bench": 0.6, "filtering": 0.2, "perspective": 0.2}
#: Each suite's command-line options per part. ``tiny`` is what the test runs on a software adapter in seconds.
SUITE_OPTIONS = {
    "full": {part: ("--suite", "full") for part in PARTS},
    "smoke": {part: ("--suite", "smoke") for part in PARTS},
    # bench's full sweep of maps, angles and configurations at a frame a software adapter renders in minutes
    "reduced": {"bench": ("--suite", "full", "--resolution", "192x108", "--frames", "3"),
                "filtering": ("--suite", "smoke"), "perspective": ("--suite", "smoke")},
    "tiny": {
        "bench": ("--suite", "smoke", "--heightmaps", "bricks", "--angles", "0,60", "--techniques", "basic,pom",
                  "--resolution", "32x18", "--frames", "2"),
        "filtering": ("--suite", "smoke", "--size", "16x12", "--frames", "1", "--reliefs", "bricks", "--albedos",
                      "own", "--angles", "80", "--footprints", "2", "--filters", "trilinear"),
        "perspective": ("--suite", "smoke"),
    },
}
BUDGET_S = 480.0  # one 8-minute device call
#: Kept back from the parts' boxes: a stopped part's unwinding, bench's report from the rows it kept.
RESERVE_S = 30.0
#: How long a part may take to unwind after SIGTERM before it and what it started are killed.
STOP_GRACE_S = 15.0
MANIFEST = "manifest.json"
OUTPUT_LINES = 40  # the last lines of a part's output (progress bars left out) the manifest keeps
#: tqdm's progress line: "bench:  37%|███▋      | 1670/4500 [00:12<00:20, ...]".
PROGRESS = re.compile(r"\|\s*(\d+)/(\d+) \[")


def adapter_slug(device: str) -> str:
    """The folder name of an adapter: its device name before any parenthesis, lower case, words joined by '-'
    ("NVIDIA H200" -> nvidia-h200, "llvmpipe (LLVM 15.0.6, 256 bits)" -> llvmpipe)."""
    slug = re.sub(r"[^a-z0-9]+", "-", device.split("(")[0].lower()).strip("-")
    return slug or "adapter"


def run_folder_name(slug: str, suite: str) -> str:
    return slug if suite == "full" else f"{slug}-{suite}"


def limited_to_few_sms(adapter: str) -> bool:
    """Hopper data-centre parts (H100, H200) run fragment shaders on 4 of their 132 SMs."""
    return "H100" in adapter or "H200" in adapter


# --- running the parts ---------------------------------------------------------------------------------------


@dataclass
class PartOutput:
    """A part's output, read while it runs: progress-bar redraws are not kept except the last one; every other
    line is (the last ``OUTPUT_LINES``)."""

    progress: str = ""
    lines: list[str] = field(default_factory=list)

    def read(self, stream) -> None:
        pending = b""
        for chunk in iter(lambda: stream.read1(65536), b""):
            pending += chunk
            *done, pending = re.split(rb"[\r\n]", pending)
            for raw in done:
                self.take(raw)
        self.take(pending)

    def take(self, raw: bytes) -> None:
        line = raw.decode("utf-8", "replace").strip()
        if not line:
            return
        if PROGRESS.search(line):
            self.progress = line
        else:
            self.lines = [*self.lines[-(OUTPUT_LINES - 1):], line]


def part_command(part: str, suite: str, out: Path, backend: str | None) -> list[str]:
    """The command line of ``part`` (after ``wgpuviewer``) writing into ``out``."""
    inside = out.resolve().is_relative_to(Path.cwd().resolve())  # the reports record it: short where it can be
    command = [part, *SUITE_OPTIONS[suite][part], "--out", os.path.relpath(out) if inside else str(out)]
    return command + (["--backend", backend] if backend else [])


def run_part(command: list[str], box_s: float) -> dict:
    """Run ``wgpuviewer COMMAND`` as a child process for at most ``box_s`` seconds: at the box's end it gets SIGTERM
    (it unwinds like Ctrl-C) and ``STOP_GRACE_S`` to end, then it and every process it started are killed. Its
    record: status (finished, stopped or failed), exit code, seconds, last progress line and output."""
    output = PartOutput()
    start = time.monotonic()
    child = subprocess.Popen([sys.executable, "-m", "wgpuviewer", *command], stdout=subprocess.PIPE,
                             stderr=subprocess.STDOUT, process_group=0,  # its own group, in this session
                             env={**os.environ, "PYTHONUNBUFFERED": "1"})
    reader = threading.Thread(target=output.read, args=(child.stdout,), daemon=True)
    reader.start()
    stopped = False
    try:
        try:
            child.wait(timeout=box_s)
        except subprocess.TimeoutExpired:
            stopped = True
            child.send_signal(signal.SIGTERM)
            with contextlib.suppress(subprocess.TimeoutExpired):  # still running: killed below
                child.wait(timeout=STOP_GRACE_S)
    finally:  # also when this command is interrupted: nothing of a stopped part outlives it
        if stopped or child.returncode is None:
            with contextlib.suppress(ProcessLookupError, PermissionError):  # its group may have ended already
                os.killpg(child.pid, signal.SIGKILL)
        child.wait()
        reader.join(timeout=5.0)
        child.stdout.close()
    status = "stopped" if stopped else "finished" if child.returncode == 0 else "failed"
    return {"status": status, "exit_code": child.returncode, "seconds": round(time.monotonic() - start, 1),
            "progress": output.progress, "output": output.lines}


def csv_rows(path: Path) -> int:
    """The data rows of a results file (0 when there is none)."""
    if not path.is_file():
        return 0
    with open(path, newline="", encoding="utf-8") as f:
        return max(sum(1 for _ in csv.reader(f)) - 1, 0)


def report_kept_bench_rows(folder: Path, command: str) -> str:
    """bench's report.md and plots from the rows a stopped or failed bench kept (it writes results.csv view by
    view); what the manifest says about it."""
    from wgpuviewer.lab.bench.run import rereport

    try:
        rereport([folder / "results.csv"], folder, command)
    except UserError as error:
        return f"its report could not be made from the rows it kept: {error}"
    return "report.md and plots made from the rows it kept"


@dataclass
class Plan:
    """How the budget is cut into time boxes: ``fixed`` boxes (``--box``) first, the rest by ``SHARES``."""

    parts: tuple[str, ...]
    budget_s: float
    fixed: dict[str, float]

    def box(self, part: str, left_s: float) -> float:
        """``part``'s time box when ``left_s`` seconds are left to it and the parts after it."""
        later = self.parts[self.parts.index(part):]
        if part in self.fixed:
            return min(self.fixed[part], left_s)
        shared = [p for p in later if p not in self.fixed]
        free = left_s - sum(min(self.fixed[p], left_s) for p in later if p in self.fixed)
        return max(free, 0.0) * SHARES[part] / sum(SHARES[p] for p in shared)


def utc_now() -> str:
    return datetime.datetime.now(datetime.UTC).strftime("%Y-%m-%dT%H:%M:%SZ")


def run_suite(args, plan: Plan, run_dir: Path, adapter: str, software: bool, command: str) -> dict:
    """Every part of ``plan`` in turn within its box; the manifest is written after each one, so it says what
    finished also when the run itself is killed."""
    start = time.monotonic()
    manifest = {"command": command, "suite": args.suite, "adapter": adapter, "software": software,
                "started": utc_now(), "seconds": 0.0, "budget_s": plan.budget_s, "parts": []}
    for part in plan.parts:
        folder = run_dir / part
        left = plan.budget_s - RESERVE_S - (time.monotonic() - start)
        box = plan.box(part, left)
        record = {"name": part, "folder": part, "box_s": round(box, 1)}
        if box < 1.0:
            record.update(status="skipped", detail=f"not started: {max(left, 0.0):.0f} s of the "
                          f"{plan.budget_s:g} s budget were left")
        else:
            words = part_command(part, args.suite, folder, args.backend)
            record["command"] = command_line("wgpuviewer", words)
            print(f"{PROG}: {part}: at most {box:.0f} s", file=sys.stderr)
            record.update(run_part(words, box))
            record["rows"] = csv_rows(folder / "results.csv")
            record["detail"] = describe(record)
            if part == "bench" and record["status"] != "finished" and record["rows"]:
                record["detail"] += "; " + report_kept_bench_rows(folder, record["command"])
            print(f"{PROG}: {part}: {record['detail']}", file=sys.stderr)
        manifest["parts"].append(record)
        manifest["seconds"] = round(time.monotonic() - start, 1)
        write_bytes(run_dir / MANIFEST, (json.dumps(manifest, indent=2, ensure_ascii=False) + "\n").encode())
    return manifest


def rows_text(n: int) -> str:
    return f"{n} row{'s' * (n != 1)}"


def describe(record: dict) -> str:
    """One sentence on how a part ended."""
    if record["status"] == "finished":
        return f"finished in {record['seconds']:.0f} s, {rows_text(record['rows'])}"
    if record["status"] == "stopped":
        done = PROGRESS.search(record["progress"])
        return (f"stopped at its {record['box_s']:.0f} s time box" +
                (f" after {done[1]} of {done[2]} steps" if done else "") + f"; {rows_text(record['rows'])} kept")
    last = record["output"][-1] if record["output"] else "no output"
    return f"failed (exit code {record['exit_code']}) after {record['seconds']:.0f} s: {last}"


def prepare_run_folder(run_dir: Path) -> None:
    """An earlier run of the same adapter and suite in ``run_dir`` is replaced (git keeps a committed one): its
    manifest and part folders go; a folder that is not such a run is refused."""
    if run_dir.is_dir():
        if not (run_dir / MANIFEST).is_file() and any(run_dir.iterdir()):
            raise UserError(f"{run_dir}: exists and is not a gpu-suite run (no {MANIFEST}); move it away or give "
                            "another --out-root")
        for part in PARTS:
            shutil.rmtree(run_dir / part, ignore_errors=True)
        (run_dir / MANIFEST).unlink(missing_ok=True)
    output_dir(run_dir, "--out-root")


# --- the README's headline -----------------------------------------------------------------------------------


@dataclass(frozen=True)
class Run:
    folder: Path
    manifest: dict

    @property
    def bench(self) -> dict | None:
        return next((p for p in self.manifest["parts"] if p["name"] == "bench"), None)

    @property
    def results(self) -> Path:
        return self.folder / "bench" / "results.csv"


def load_runs(out_root: Path) -> list[Run]:
    """The gpu-suite runs under ``out_root`` whose bench kept rows."""
    runs = []
    for path in sorted(out_root.glob(f"*/{MANIFEST}")):
        try:
            manifest = json.loads(path.read_text(encoding="utf-8"))
        except (OSError, ValueError) as error:
            raise UserError(f"{path}: not a gpu-suite manifest ({error}); remove the folder or run again") from None
        run = Run(path.parent, manifest)
        if run.bench is not None and csv_rows(run.results):
            runs.append(run)
    return runs


#: How much of bench's sweep a suite measures: the headline shows the widest run (the most informative table).
SUITE_RANK = {"full": 3, "reduced": 2, "smoke": 1, "tiny": 0}


def headline_run(runs: list[Run]) -> Run | None:
    """The run on a real GPU before any on a software adapter; among those, one whose bench finished before one
    stopped early, then the widest suite, then the newest."""
    return max(runs, key=lambda r: (not r.manifest["software"], r.bench["status"] == "finished",
                                    SUITE_RANK.get(r.manifest["suite"], 0), r.manifest["started"]), default=None)


def _link(target: Path, base: Path) -> str:
    return Path(os.path.relpath(target, base)).as_posix()


def _label(config: tuple[str, str]) -> str:
    technique, params = config
    return f"`{technique}`" + ("" if params == "-" else f" {params}")


def _geomean(values: list[float]) -> float:
    values = [v for v in values if v > 0 and math.isfinite(v)]
    return math.exp(sum(map(math.log, values)) / len(values)) if values else float("nan")


def _number(x: float, digits: int = 2) -> str:
    return f"{x:.{digits}f}" if math.isfinite(x) else "–"


def headline_markdown(out_root: Path, readme_dir: Path) -> str:
    """The README's headline section: bench's headline rule (``bench.report.headline``) on the bench results of
    ``headline_run``, the adapter named plainly, what each part of that run did, and on an H100/H200 what its
    milliseconds mean; links relative to ``readme_dir``."""
    from wgpuviewer.lab.bench.report import HEADLINE_MAX_ANGLE, REFERENCE_CONFIG, config_key, headline, reference_cost
    from wgpuviewer.lab.bench.run import TABLE

    run = headline_run(load_runs(out_root))
    if run is None:
        return (f"No `./dev gpu-suite` run with bench results is under `{_link(out_root, readme_dir)}/` yet: run it "
                "on a GPU ([`docs/benchmarks.md`](docs/benchmarks.md#the-gpu-run-dev-gpu-suite)).")
    m = run.manifest
    rows = TABLE.read(run.results)
    folder = _link(run.folder, readme_dir)
    kind = "a software adapter, not a GPU" if m["software"] else "a GPU"
    date = m["started"].replace("T", " ").removesuffix("Z")[:16] + " UTC"
    maps = list(dict.fromkeys(r["heightmap"] for r in rows))
    angles = sorted({r["angle"] for r in rows})
    configs = list(dict.fromkeys(config_key(r) for r in rows))
    lines = [f"Adapter: **{m['adapter']}** ({kind}), {date}, `./dev gpu-suite --suite {m['suite']}` "
             f"([`{folder}/`]({folder}/{MANIFEST})). bench ([report]({folder}/bench/report.md)): "
             f"{len(maps)} height map{'s' * (len(maps) > 1)} ({', '.join(maps)}) × {len(angles)} angles, "
             f"{rows[0]['resolution']}, "
             f"{len(configs)} configurations; {run.bench['detail']}."]
    for part in m["parts"]:
        if part["name"] == "bench":
            continue
        report = run.folder / part["folder"] / "report.md"
        link = f" ([report]({folder}/{part['folder']}/report.md))" if report.is_file() else ""
        lines.append(f"{part['name']}{link}: {part['detail']}.")
    lines.append("")
    reference = reference_cost(rows)
    lines += ["| p95 budget | cheapest | × basic | ms per frame | SIMD-tile fetches | "
              f"vs {_label(REFERENCE_CONFIG)} |", "|---|---|---|---|---|---|"]
    for best in headline(rows):
        budget = f"≤ {best['budget']:g} texel"
        if best["config"] is None:
            lines.append(f"| {budget} | none of the measured configurations | – | – | – | – |")
            continue
        ms = _geomean([r["gpu_ms"] for r in rows
                       if config_key(r) == best["config"] and r["angle"] <= HEADLINE_MAX_ANGLE])
        versus = "not measured" if reference is None else "itself" if best["config"] == REFERENCE_CONFIG else (
            f"{_number(best['simd'] / reference['simd'], 3)}× its SIMD-tile fetches, "
            f"{_number(best['ratio'] / reference['ratio'])}× its time")
        lines.append(f"| {budget} | {_label(best['config'])} | {_number(best['ratio'])} | {_number(ms, 3)} | "
                     f"{_number(best['simd'], 1)} | {versus} |")
    lines.append("")
    if m["software"]:
        lines.append(f"**{m['adapter']} is a software adapter**: its times and milliseconds are CPU times of an "
                     "emulated GPU, and their ratios are not a GPU's; the SIMD-tile fetches are the "
                     "machine-independent part. No real-GPU run of `./dev gpu-suite` is under "
                     f"`{_link(out_root, readme_dir)}/` yet.")
    elif limited_to_few_sms(m["adapter"]):
        lines.append("**On an H100/H200 only 4 of the 132 SMs run fragment shaders**: these milliseconds use about "
                     "3 % of the chip and are not those of a desktop GPU; the ratios between techniques are "
                     "meaningful.")
    return "\n".join(lines)


# --- the command -----------------------------------------------------------------------------------------------


def build_parser() -> OneLineParser:
    parser = OneLineParser(prog=PROG, description=(
        "bench, filtering and perspective within one time budget on this machine's GPU, into "
        "OUT_ROOT/<adapter>/; `wgpuviewer docs` then makes the README's headline from the newest run "
        "(docs/benchmarks.md)"))
    parser.add_argument("--suite", choices=tuple(SUITE_OPTIONS), default="full",
                        help="full: the published measurement (default); reduced: bench's full sweep at 192x108 "
                        "(a software adapter); smoke: the CI size; tiny: seconds, for the test")
    parser.add_argument("--budget", type=float, default=BUDGET_S, metavar="SECONDS",
                        help=f"the whole run's time, all parts included (default {BUDGET_S:g}: one "
                        "8-minute device call)")
    parser.add_argument("--box", action="append", default=[], metavar="PART=SECONDS",
                        help="a part's own time box (repeatable); the other parts share what the budget leaves "
                        f"({', '.join(f'{p} {SHARES[p]:g}' for p in PARTS)})")
    parser.add_argument("--parts", default=",".join(PARTS),
                        help=f"comma-separated parts to run, in the order {', '.join(PARTS)} (default: all)")
    parser.add_argument("--allow-software", action="store_true",
                        help="run on a software adapter too (to test the command; its times are no GPU's)")
    parser.add_argument("--out-root", default=str(CHECKOUT / "benchmarks"),
                        help="where the run's folder <adapter>/ goes (default: the checkout's benchmarks/, where "
                        "`wgpuviewer docs` chooses the README's headline run from)")
    add_backend_option(parser)
    return parser


def checked_plan(args) -> Plan:
    """The parts and time boxes of the options, each value checked (a one-line error naming the option)."""
    parts = [p.strip() for p in args.parts.split(",") if p.strip()]
    unknown = [p for p in parts if p not in PARTS]
    if unknown or not parts:
        raise UserError(f"--parts {args.parts!r}: expected some of {', '.join(PARTS)}")
    if not (math.isfinite(args.budget) and args.budget > RESERVE_S):
        raise UserError(f"--budget {args.budget:g}: expected more than {RESERVE_S:g} seconds (kept back to end the "
                        "run), e.g. 480")
    fixed = {}
    for item in args.box:
        name, _, seconds = item.partition("=")
        try:
            value = float(seconds)
        except ValueError:
            value = float("nan")
        if name not in parts or not (math.isfinite(value) and value > 0):
            raise UserError(f"--box {item!r}: expected PART=SECONDS with PART one of {', '.join(parts)} and "
                            "SECONDS above 0, e.g. bench=300")
        fixed[name] = value
    return Plan(tuple(p for p in PARTS if p in parts), args.budget, fixed)


def command(argv: list[str]) -> int:
    args = build_parser().parse_args(argv)
    plan = checked_plan(args)
    out_root = output_dir(args.out_root, "--out-root")
    from wgpuviewer.core.gpu import choose_adapter, is_software

    adapter = choose_adapter(args.backend, quiet=True)
    software = is_software(adapter)
    if software and not args.allow_software:
        raise UserError(f"the adapter is {adapter.summary}, a software adapter: its times are CPU times, no GPU's. "
                        "Run this on a machine with a GPU (--backend picks another adapter), or pass "
                        "--allow-software to test the command")
    run_dir = out_root / run_folder_name(adapter_slug(adapter.info.get("device") or adapter.summary), args.suite)
    prepare_run_folder(run_dir)
    print(f"{PROG}: {adapter.summary} -> {run_dir} ({args.suite} suite, {args.budget:g} s budget)", file=sys.stderr)
    manifest = run_suite(args, plan, run_dir, adapter.summary, software, command_line("./dev", [PROG, *argv]))
    print(f"{PROG}: README.md's headline is not written by a run: `wgpuviewer docs` makes it again from "
          f"{CHECKOUT / 'benchmarks'}", file=sys.stderr)
    print(run_dir / MANIFEST)
    return 0 if all(p["status"] == "finished" for p in manifest["parts"]) else 1


def main(argv: list[str] | None = None) -> int:
    """Exit codes: 0 every part finished, 1 a part stopped at its time box, failed or was skipped (the manifest
    says which), 2 a user error (an option, a software adapter without --allow-software), 3 an internal error."""
    prepare_process(PROG)
    given = list(sys.argv[1:] if argv is None else argv)
    try:
        return run_command(PROG, lambda: command(given))
    except SystemExit as exit_:  # argparse: --help (0) and usage errors (2, one line)
        return int(exit_.code or 0)


if __name__ == "__main__":
    sys.exit(main())
