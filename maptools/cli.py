"""``maptools`` command line: generate one map, batch-generate many, or check GPU against CPU.

Exit codes: 0 success, 1 a batch job or a check failed, 2 a user error (one line on stderr), 3 an internal error
(one line; the traceback is saved to a file whose path it prints; a batch goes on past it and reports it).
"""

from __future__ import annotations

import argparse
import hashlib
import json
import sys
import threading
import time
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

from wgpuviewer.core.commands import OneLineParser, prepare_process, run_command, save_traceback, terminal_progress
from wgpuviewer.core.errors import FileError, UserError
from wgpuviewer.core.images import HEIGHT_CHANNELS, NAN_POLICIES, read_height
from wgpuviewer.core.io import output_dir, refuse_directory, remove_stale_temps
from wgpuviewer.core.sidecar import MapRecord, file_sha256, is_recorded, read_record, record_path, write_record

from . import VERSION, generate, resolve_backend
from .check import DEFAULT_SAMPLE, DEFAULT_SEED, check_kinds, sampled_kinds
from .io import INPUT_EXTS, write_result
from .registry import KINDS, get_kind

#: What a height-map input may be (core.images reads them).
INPUT_HELP = "8/16-bit PNG, JPEG, TIFF, EXR or a float .npy array in [0, 1]"


def _version() -> str:
    """maptools' version: the installed wgpuviewer distribution's, and the CPU references' (part of every map key)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        installed = version("wgpuviewer")
    except PackageNotFoundError:
        installed = "(not installed: pip install -e . in the checkout)"
    return f"{installed} (wgpuviewer distribution; CPU references {VERSION})"


def _flag(name: str) -> str:
    return "--" + name.replace("_", "-")


def _add_input_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--channel", default="auto", choices=HEIGHT_CHANNELS,
                   help="channel of a colour input (default %(default)s: a grey file as it is, a colour one as its "
                   "Rec. 709 luma; grey: refuse a colour file; r, g, b, a: that channel; luma: Rec. 709 luma)")
    p.add_argument("--nan-policy", default="error", choices=NAN_POLICIES,
                   help="NaN/inf texels (float inputs): error (refuse), zero, nearest (the nearest finite texel's "
                   "value); default %(default)s")


def _add_backend(p: argparse.ArgumentParser) -> None:
    p.add_argument("--backend", default="auto", choices=("auto", "gpu", "cpu"),
                   help="where the maps are computed: gpu, cpu (the OpenCV/numpy reference), or auto (default): the "
                   "GPU when an adapter exists, else the CPU")


def _parse_kinds(text: str | None) -> list[str]:
    """--kinds: None (not given) means every kind; a given list must name at least one."""
    if text is None:
        return list(KINDS)
    names = [t.strip() for t in text.split(",") if t.strip()]
    if not names:
        raise UserError(f"--kinds {text!r}: expected a comma-separated list of kinds, e.g. normal,maxmip "
                        "(omit --kinds for all)")
    for n in names:
        get_kind(n)
    return list(dict.fromkeys(names))


def kind_options(kinds: list[str], items: list[str] | None) -> dict[str, dict]:
    """The resolved options of each selected kind from --set KIND.OPTION=VALUE (repeatable). Every --set is
    validated like a selected kind's, then one naming a kind that is not selected is refused: it would change
    nothing, and a batch that silently ignores an option is discovered only when its maps are used."""
    sets: dict[str, dict] = {}
    given: dict[str, str] = {}
    for item in items or []:
        head, eq, value = item.partition("=")
        kind, dot, opt = head.partition(".")
        if not eq or not dot:
            raise UserError(f"--set {item!r}: expected KIND.OPTION=VALUE, e.g. complexity.levels=16")
        get_kind(kind)
        sets.setdefault(kind, {})[opt.replace("-", "_")] = value
        given.setdefault(kind, item)
    resolved = {k: get_kind(k).resolve(sets.get(k, {})) for k in dict.fromkeys([*sets, *kinds])}
    for kind, item in given.items():
        if kind not in kinds:
            raise UserError(f"--set {item!r}: {kind} is not among the kinds selected ({', '.join(kinds)}); "
                            f"add it to --kinds or drop the --set")
    return {k: resolved[k] for k in kinds}


def build_parser() -> argparse.ArgumentParser:
    parser = OneLineParser(prog="maptools", description="Generate maps derived from height maps.")
    parser.add_argument("--version", action="version", version=f"%(prog)s {_version()}")
    sub = parser.add_subparsers(dest="command", required=True, metavar="COMMAND")

    gen = sub.add_parser("generate", help="generate one map from one height map")
    gen_kinds = gen.add_subparsers(dest="kind", required=True, metavar="KIND")
    for kind in KINDS.values():
        kp = gen_kinds.add_parser(kind.name, help=kind.description, description=kind.description)
        kp.add_argument("input", metavar="INPUT", help=f"height map file ({INPUT_HELP})")
        kp.add_argument("-o", "--output", required=True, metavar="OUT",
                        help=f"output file ({', '.join(kind.extensions)})")
        _add_backend(kp)
        _add_input_options(kp)
        kp.add_argument("--bits", type=int, default=8, choices=(8, 16), help="PNG bit depth (default %(default)s)")
        for opt in kind.options:
            kp.add_argument(_flag(opt.name), dest=f"opt_{opt.name}", default=None, metavar=opt.name.upper(),
                            choices=opt.choices and [str(c) for c in opt.choices],
                            help=f"{opt.help} (default {opt.default})")

    bat = sub.add_parser("batch", help="generate maps for many height maps (files and folders)")
    bat.add_argument("inputs", nargs="+", metavar="INPUT",
                     help=f"height map files ({INPUT_HELP}) and folders (searched recursively for "
                     f"{', '.join(INPUT_EXTS)} files; maps this tool wrote are skipped)")
    bat.add_argument("-o", "--output", required=True, metavar="DIR",
                     help="output folder (created if missing): INPUT_STEM.KIND.EXT per map, each with a "
                     "INPUT_STEM.KIND.EXT.json sidecar recording its source and options (reruns skip up-to-date maps)")
    bat.add_argument("--kinds", default=None, help=f"comma-separated kinds (default all: {','.join(KINDS)})")
    bat.add_argument("--jobs", type=int, default=1,
                     help="worker threads reading and writing files (default %(default)s; GPU work is serialised)")
    bat.add_argument("--shard", default=None, metavar="I/N", help="process only sorted inputs i with i %% N == I")
    bat.add_argument("--force", action="store_true", help="regenerate even when outputs are up to date")
    bat.add_argument("--set", action="append", metavar="KIND.OPTION=VALUE",
                     help="a kind's option, e.g. complexity.levels=16 (repeatable; `maptools kinds` lists them)")
    bat.add_argument("--bits", type=int, default=8, choices=(8, 16), help="PNG bit depth (default %(default)s)")
    _add_backend(bat)
    _add_input_options(bat)

    chk = sub.add_parser("check", help="run GPU and CPU paths and compare them against each kind's tolerance")
    chk.add_argument("input", metavar="INPUT", help=f"height map file ({INPUT_HELP})")
    chk.add_argument("--kinds", default=None, help="comma-separated kinds (default all)")
    chk.add_argument("--set", action="append", metavar="KIND.OPTION=VALUE",
                     help="a kind's option, e.g. complexity.levels=16 (repeatable; `maptools kinds` lists them)")
    chk.add_argument("--full", action="store_true",
                     help="compare every value of every kind (the slow CPU references in full: minutes on a 512x512 "
                     "map); default: those kinds at a seeded random sample of values")
    chk.add_argument("--sample", type=int, default=None, metavar="N",
                     help=f"values compared per sampled kind ({', '.join(sampled_kinds())}; default {DEFAULT_SAMPLE})")
    chk.add_argument("--seed", type=int, default=None, metavar="S",
                     help=f"seed of the sample (default {DEFAULT_SEED})")
    _add_input_options(chk)

    sub.add_parser("kinds", help="list the map kinds and their options")

    cac = sub.add_parser("cache", help="the renderer's map cache: where it is, how big, and emptying it")
    cac_actions = cac.add_subparsers(dest="action", required=True, metavar="ACTION")
    cac_actions.add_parser("info", help="location, size cap, maps per kind")
    cln = cac_actions.add_parser("clean", help="remove cached maps (all, or those unused for a while)")
    cln.add_argument("--older-than", metavar="AGE", help="only maps not used for AGE, e.g. 30m, 12h, 7d, 2w")

    ben = sub.add_parser("bench", help="GPU vs CPU time per kind and size, side by side (one run, same machine)")
    ben.add_argument("--kinds", default=None, help="comma-separated kinds (default all)")
    ben.add_argument("--sizes", default="64,256,1024",
                     help="comma-separated square sizes for the 2D kinds (default %(default)s)")
    for kind in KINDS.values():  # a kind timed at sizes of its own has its flag
        if kind.bench is not None:
            ben.add_argument(_flag(kind.bench.attr), default=kind.bench.default, help=kind.bench.help)
    ben.add_argument("--repeat", type=int, default=3,
                     help="timed runs per cell, the best is reported (default %(default)s)")
    return parser


# -- generate ---------------------------------------------------------------------------------------

def cmd_generate(args) -> int:
    kind = get_kind(args.kind)
    opts = {o.name: getattr(args, f"opt_{o.name}") for o in kind.options if getattr(args, f"opt_{o.name}") is not None}
    opts = kind.resolve(opts)
    out = Path(args.output)
    refuse_directory(out, f"{Path(args.input).stem}.{kind.name}{kind.extensions[0]}")
    if out.suffix.lower() not in kind.extensions:
        raise UserError(f"{out}: {kind.name} maps are written as {', '.join(kind.extensions)}")
    height = read_height(args.input, args.channel, args.nan_policy)
    result = generate(kind.name, height, backend=args.backend, **opts)
    write_result(kind, result, out, args.bits)
    print(f"wrote {out}")
    return 0


# -- batch ------------------------------------------------------------------------------------------

def _output_name(f: Path) -> bool:
    """Named like a batch output: STEM.KIND.EXT for a known kind and one of its extensions."""
    stem, _, kind = f.stem.rpartition(".")
    return bool(stem) and kind in KINDS and f.suffix.lower() in KINDS[kind].extensions


def is_output(f: Path, folder: Path, outdir: Path | None) -> bool:
    """A map this tool wrote, found while searching input ``folder``: it has a batch record (``NAME.json``,
    ``wgpuviewer.core.sidecar``), or it lies in the output folder and is named like an output, or the output folder
    lies inside ``folder`` (then nothing in it is an input)."""
    if is_recorded(f):
        return True
    if outdir is None:
        return False
    out, here = outdir.resolve(), f.resolve()
    if not here.is_relative_to(out):
        return False
    return _output_name(f) or out != folder.resolve()


def collect_inputs(paths: list[str], outdir: Path | None = None) -> tuple[list[Path], list[tuple[str, str]]]:
    """Sorted, de-duplicated input files (folders searched recursively for .png/.npy) and missing paths.
    Outputs are never inputs (``is_output``): a folder's search leaves them out; a file given by name is
    taken as given."""
    files: set[Path] = set()
    missing = []
    for p in map(Path, paths):
        if p.is_dir():
            files.update(f for f in p.rglob("*") if f.is_file() and f.suffix.lower() in INPUT_EXTS
                         and not is_output(f, p, outdir))
        elif p.is_file():
            files.add(p)
        else:
            missing.append((str(p), "no such file or folder"))
    return sorted(files, key=str), missing


def parse_shard(text: str | None) -> tuple[int, int]:
    if text is None:
        return 0, 1
    try:
        i, n = (int(x) for x in text.split("/"))
    except ValueError:
        raise UserError(f"--shard {text!r}: expected I/N, e.g. 0/4") from None
    if n < 1 or not 0 <= i < n:
        raise UserError(f"--shard {text!r}: need N >= 1 and 0 <= I < N")
    return i, n


def shard(items: list, i: int, n: int) -> list:
    return [x for k, x in enumerate(items) if k % n == i]


def job_key(digest: str, kind: str, opts: dict, args, ext: str) -> str:
    blob = json.dumps({"input_sha256": digest, "kind": kind, "options": opts, "version": VERSION,
                       "kernels": get_kind(kind).source_hash(),
                       "channel": args.channel, "nan_policy": args.nan_policy, "bits": args.bits, "ext": ext},
                      sort_keys=True)
    return hashlib.sha256(blob.encode()).hexdigest()


def up_to_date(out: Path, key: str) -> bool:
    """``out`` exists and its record names this job (an older record's layout: not up to date)."""
    try:
        return out.is_file() and read_record(out).key == key
    except FileError:
        return False


def _plan_batch(files: list[Path], kinds: list[str], outdir: Path, rows: list) -> dict[Path, list[tuple[str, Path]]]:
    """Per input, its (kind, output) jobs; two inputs with one stem would overwrite each other: the second one's
    job is a FAILED row."""
    claimed: dict[Path, Path] = {}  # output -> input
    by_input: dict[Path, list[tuple[str, Path]]] = {}
    for f in files:
        for k in kinds:
            out = outdir / f"{f.stem}.{k}{get_kind(k).extensions[0]}"
            if out in claimed:
                rows.append((str(f), k, "FAILED", f"output {out.name} already produced from {claimed[out]}"))
                continue
            claimed[out] = f
            by_input.setdefault(f, []).append((k, out))
    return by_input


def _batch_job(f: Path, digest: str, k: str, out: Path, opts: dict, args, backend: str, height):
    """One map of a batch: (its table row, the height map read, if it had to be read)."""
    kind = get_kind(k)
    key = job_key(digest, k, opts, args, out.suffix.lower())
    t0 = time.perf_counter()
    try:
        if not args.force and up_to_date(out, key):
            return (str(f), k, "skipped", "up to date"), height
        for owned in (out, record_path(out)):  # left by a killed earlier run: this job owns both
            remove_stale_temps(owned)
        if height is None:
            height = read_height(f, args.channel, args.nan_policy)
        result = generate(k, height, backend=backend, **opts)
        write_result(kind, result, out, args.bits)
        write_record(out, MapRecord(key=key, kind=k, options=opts, version=VERSION, kernels=kind.source_hash(),
                                    input=str(f), input_sha256=digest, channel=args.channel,
                                    output_sha256=file_sha256(out)))
        return (str(f), k, "ok", f"{out.name} ({time.perf_counter() - t0:.2f} s, {backend})"), height
    except UserError as exc:
        return (str(f), k, "FAILED", str(exc)), height
    except Exception as exc:  # noqa: BLE001 - a bug: report it, keep going with the other jobs
        saved = save_traceback("maptools", exc)
        return (str(f), k, "INTERNAL", f"{type(exc).__name__}: {exc} (a bug; traceback "
                                       f"{f'saved to {saved}' if saved else 'not saved'})"), height


def _batch_summary(rows: list, files: list, si: int, sn: int) -> int:
    """Print the table and the counts; the exit code (3: an internal error, 1: a failed job)."""
    print_table(rows)
    failed = sum(r[2] in ("FAILED", "INTERNAL") for r in rows)
    internal = sum(r[2] == "INTERNAL" for r in rows)
    done = sum(r[2] == "ok" for r in rows)
    skipped = sum(r[2] == "skipped" for r in rows)
    print(f"{done} generated, {skipped} up to date, {failed} failed"
          + (f" ({internal} internal error(s): please report them)" if internal else "")
          + (f" (shard {si}/{sn}: {len(files)} input(s))" if sn > 1 else ""))
    return 3 if internal else 1 if failed else 0


def cmd_batch(args) -> int:
    kinds = _parse_kinds(args.kinds)
    kopts = kind_options(kinds, args.set)
    si, sn = parse_shard(args.shard)
    if args.jobs < 1:
        raise UserError(f"--jobs {args.jobs}: must be >= 1")
    outdir = output_dir(args.output, "-o")
    files, missing = collect_inputs(args.inputs, outdir)
    files = shard(files, si, sn)
    backend = resolve_backend(args.backend) if files else "cpu"
    rows: list[tuple[str, str, str, str]] = [(p, "-", "FAILED", msg) for p, msg in missing]
    by_input = _plan_batch(files, kinds, outdir, rows)
    try:
        from tqdm import tqdm
        bar = tqdm(total=sum(map(len, by_input.values())), unit="map", desc="maptools", file=sys.stderr, disable=None)
    except ImportError:  # pragma: no cover - tqdm is a dependency
        bar = None
    lock = threading.Lock()

    def run_input(f: Path) -> list:
        try:
            digest = hashlib.sha256(f.read_bytes()).hexdigest()
        except OSError as exc:
            return [(str(f), k, "FAILED", f"cannot read: {exc.strerror or exc}") for k, _ in by_input[f]]
        res, height = [], None
        for k, out in by_input[f]:
            try:
                row, height = _batch_job(f, digest, k, out, kopts[k], args, backend, height)
                res.append(row)
            finally:
                if bar is not None:
                    with lock:
                        bar.update(1)
        return res

    try:
        if args.jobs == 1:
            results = [run_input(f) for f in by_input]
        else:
            with ThreadPoolExecutor(max_workers=args.jobs) as pool:
                results = list(pool.map(run_input, list(by_input)))
    finally:
        if bar is not None:
            bar.close()
    for r in results:
        rows.extend(r)
    return _batch_summary(rows, files, si, sn)


def print_table(rows) -> None:
    if not rows:
        print("nothing to do")
        return
    head = ("input", "kind", "status", "detail")
    widths = [max(len(head[c]), *(len(r[c]) for r in rows)) for c in range(3)]
    fmt = "  ".join(f"{{:<{w}}}" for w in widths) + "  {}"
    print(fmt.format(*head))
    for r in rows:
        print(fmt.format(*r))


# -- check ------------------------------------------------------------------------------------------

def _sampling(args) -> tuple[int | None, int]:
    """(values per sampled kind, or None for --full; seed) from --full, --sample, --seed."""
    if args.full and (args.sample is not None or args.seed is not None):
        raise UserError("--full compares every value: drop --sample and --seed, or drop --full")
    if args.sample is not None and args.sample < 1:
        raise UserError(f"--sample {args.sample}: must be >= 1 (or --full for every value)")
    if args.seed is not None and args.seed < 0:
        raise UserError(f"--seed {args.seed}: must be >= 0")
    seed = DEFAULT_SEED if args.seed is None else args.seed
    return None if args.full else DEFAULT_SAMPLE if args.sample is None else args.sample, seed


def cmd_check(args) -> int:
    from tqdm import tqdm

    from . import gpu

    kinds = _parse_kinds(args.kinds)
    kopts = kind_options(kinds, args.set)
    sample, seed = _sampling(args)
    height = read_height(args.input, args.channel, args.nan_policy)
    g = gpu.runner()  # NoAdapterError (exit 2) when there is no GPU to check
    print(f"{args.input}: {height.shape[1]}x{height.shape[0]} on {g.gpu.summary}")
    sampled = [k for k in kinds if get_kind(k).sampled is not None]
    if sample is None or not sampled:
        print("comparing every value of every kind")
    else:
        print(f"{', '.join(sampled)}: CPU reference at a random sample of {sample} values per kind (seed {seed}; "
              f"--sample, --seed change it, --full compares every value)")
    width = max(map(len, kinds))
    bad = 0
    started = time.perf_counter()
    with terminal_progress("maptools check") as progress:
        for r in check_kinds(height, kinds, kopts, sample, seed, progress):
            c, kind = r.comparison, get_kind(r.kind)
            bad += not c.ok
            with tqdm.external_write_mode(file=sys.stdout):  # the line above the progress bar, not through it
                print(f"{r.kind:<{width}}  max {c.max_diff:.3g}  mean {c.mean_diff:.3g}  tolerance: {kind.tolerance}  "
                      f"{'OK' if c.ok else 'MISMATCH'}" + (f"  ({c.detail})" if c.detail else "")
                      + f"  [{r.describe(seed)}]", flush=True)
    print(f"{len(kinds) - bad} of {len(kinds)} kinds within tolerance in {time.perf_counter() - started:.1f} s")
    return 1 if bad else 0


def parse_age(text: str) -> float:
    """'30s', '15m', '12h', '7d', '2w' -> seconds."""
    units = {"s": 1, "m": 60, "h": 3600, "d": 86400, "w": 7 * 86400}
    number, unit = text.strip()[:-1], text.strip()[-1:].lower()
    try:
        value = float(number)
    except ValueError:
        value = -1.0
    if unit not in units or not value >= 0:
        raise UserError(f"--older-than {text!r}: expected an age such as 30m, 12h, 7d or 2w")
    return value * units[unit]


def cmd_bench(args) -> int:
    from .bench import cmd_bench as bench

    return bench(args, _parse_kinds(args.kinds))


def cmd_cache(args) -> int:
    from . import cache

    if args.action == "info":
        print(cache.describe())
        return 0
    age = parse_age(args.older_than) if args.older_than else None
    removed = cache.clean(age)
    freed = sum(e.size for e in removed) / 2**20
    print(f"removed {len(removed)} maps ({freed:.1f} MiB) from {cache.cache_dir()}"
          + (f" not used for {args.older_than}" if age is not None else ""))
    return 0


def cmd_kinds(args) -> int:
    for kind in KINDS.values():
        print(f"{kind.name}: {kind.description}")
        print(f"  outputs: {', '.join(kind.extensions)}; GPU vs CPU: {kind.tolerance}")
        for o in kind.options:
            print(f"  {_flag(o.name)} (default {o.default}): {o.help}")
    return 0


def main(argv=None) -> int:
    """Exit codes (wgpuviewer.core.commands): 0 ok, 1 a batch job or check failed, 2 a user error, 3 an internal error."""
    prepare_process("maptools")  # before any GPU driver loads
    try:
        args = build_parser().parse_args(argv)
    except SystemExit as exc:  # argparse: usage errors (2, one line) and --help (0)
        return int(exc.code or 0)
    commands = {"generate": cmd_generate, "batch": cmd_batch, "check": cmd_check, "kinds": cmd_kinds,
                "bench": cmd_bench, "cache": cmd_cache}
    return run_command("maptools", lambda: commands[args.command](args))


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
