"""Command line: ``wgpuviewer view|render|techniques|info``."""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import BACKEND_CHOICES, BACKEND_ENV
from wgpuviewer.relief.output import OUTPUT_MODES

DEFAULT_SIZE = (1280, 720)


def parse_size(text: str) -> tuple[int, int]:
    try:
        w, h = (int(part) for part in text.lower().split("x"))
    except ValueError:
        raise UserError(f"--size {text!r}: expected WIDTHxHEIGHT, e.g. 1280x720") from None
    if not (1 <= w <= 16384 and 1 <= h <= 16384):
        raise UserError(f"--size {text!r}: width and height must be 1 to 16384")
    return w, h


def load_scene_arg(path: str | None):
    from .scene import default_scene_path, load_scene

    return load_scene(Path(path) if path else default_scene_path())


def pick_technique(scene, name: str | None) -> str:
    from wgpuviewer.relief.techniques import get_technique

    return get_technique(name or scene.technique, "--technique").name


def has_display() -> bool:
    if sys.platform.startswith("linux"):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


def cmd_render(args) -> int:
    from wgpuviewer.core.gpu import get_gpu
    from wgpuviewer.relief.output import OUTPUT_SUFFIXES, save_output
    from wgpuviewer.relief.renderer import Renderer

    out = Path(args.output)
    if out.suffix.lower() not in OUTPUT_SUFFIXES:
        raise UserError(f"-o {out}: unknown output type {out.suffix!r}; use .png (image) or .npy (raw float32 data)")
    scene = load_scene_arg(args.scene)
    technique = pick_technique(scene, args.technique)
    size = parse_size(args.size) if args.size else DEFAULT_SIZE
    renderer = Renderer(scene, get_gpu(args.backend))
    save_output(out, renderer.render(technique, size), args.mode)
    print(out)
    return 0


def cmd_view(args) -> int:
    from wgpuviewer.viewer.settings import load_settings

    scripted = args.frames is not None or bool(args.screenshot)
    settings, _warnings = load_settings()  # corrupt/outdated file: defaults + a warning on stderr
    scene_arg, technique_arg = args.scene, args.technique
    window = has_display()
    if window and not scripted and scene_arg is None and settings.last_scene and Path(settings.last_scene).is_file():
        scene_arg = settings.last_scene  # interactive runs continue where the last one ended
        print(f"opening the last scene {scene_arg} (give a SCENE to open another)", file=sys.stderr)
    scene = load_scene_arg(scene_arg)
    if window and not scripted and technique_arg is None and scene_arg == settings.last_scene \
            and settings.last_technique in scene.techniques:
        technique_arg = settings.last_technique
    technique = pick_technique(scene, technique_arg)
    size = parse_size(args.size) if args.size else None
    if not window:
        from wgpuviewer.core.gpu import get_gpu
        from wgpuviewer.relief.output import save_output
        from wgpuviewer.relief.renderer import Renderer

        out = Path("out") / f"{Path(scene.path).stem if scene.path else 'scene'}_{technique}.png"
        print(f"no display found (DISPLAY/WAYLAND_DISPLAY unset): rendering the scene to {out} instead")
        renderer = Renderer(scene, get_gpu(args.backend))
        save_output(out, renderer.render(technique, size or DEFAULT_SIZE), "color")
        print(out)
        return 0
    from wgpuviewer.viewer.app import run_viewer

    keys = [k for k in args.keys.split(",") if k] if args.keys else []
    return run_viewer(
        scene, technique, backend=args.backend, frames=args.frames, screenshot=args.screenshot, keys=keys,
        gui=args.gui, settings=settings, size=size,
    )


def cmd_techniques(args) -> int:
    from wgpuviewer.relief.techniques import TECHNIQUES

    for t in TECHNIQUES.values():
        print(f"{t.key}  {t.name:<10} needs: {', '.join(t.textures):<22} cost: {t.cost}")
        print(f"   {t.description}")
        for p in t.params:
            kind = p.kind.__name__
            rng = "" if p.kind is bool else f" [{p.min:g}..{p.max:g}]"
            print(f"   - {p.name} ({kind}, default {p.default}{rng}): {p.doc}")
    return 0


def cmd_accuracy(args) -> int:
    if args.rays < 1:
        raise UserError(f"--rays {args.rays}: expected at least 1 ray")
    if not (math.isfinite(args.height_scale) and 0 < args.height_scale <= 1):
        raise UserError(f"--height-scale {args.height_scale}: expected a relief depth in (0, 1] UV units")
    if args.texels < 1:
        raise UserError(f"--texels {args.texels}: expected at least 1 texel")
    from tqdm import tqdm

    from wgpuviewer.relief.accuracy import DEFAULT_ANGLES, DEFAULT_SETTINGS, table

    from .textures import BUILTINS, builtin_height

    for name in args.heightmaps:
        if name not in BUILTINS:
            raise UserError(f"--heightmaps: unknown builtin {name!r}; expected some of {', '.join(BUILTINS)}")
    maps = {name: builtin_height(name, (args.texels, args.texels)) for name in args.heightmaps}
    total = len(maps) * len(DEFAULT_SETTINGS) * len(DEFAULT_ANGLES)
    from wgpuviewer.core.gpu import get_gpu

    gpu = get_gpu(args.backend)
    with tqdm(total=total, desc="probe vs reference", file=sys.stderr, leave=False) as bar:
        text = table(maps, height_scale=args.height_scale, rays=args.rays, backend=args.backend, progress=bar.update)
    print(f"Adapter: {gpu.summary}; height_scale {args.height_scale}; {args.rays} random rays per row; "
          f"{args.texels}x{args.texels} maps; errors over rays that were not capped.\n")
    print(text)
    return 0


def names(text: str | None, option: str) -> list[str] | None:
    """A comma-separated option value as a list (None when the option was not given)."""
    if text is None:
        return None
    items = [x.strip() for x in text.split(",") if x.strip()]
    if not items:
        raise UserError(f"{option} {text!r}: expected a comma-separated list, e.g. a,b")
    return items


def angle_list(text: str | None) -> list[float] | None:
    """--angles as degrees (None when not given)."""
    if text is None:
        return None
    try:
        return [float(x) for x in names(text, "--angles")]
    except ValueError:
        raise UserError(f"--angles {text!r}: expected comma-separated degrees, e.g. 0,45,80") from None


def cmd_bench(args) -> int:
    from wgpuviewer.bench.run import resolve_options, run

    angles = angle_list(args.angles)
    resolution = None
    if args.resolution:
        try:
            resolution = parse_size(args.resolution)
        except UserError as e:
            raise UserError(str(e).replace("--size", "--resolution")) from None
    command = "wgpuviewer " + " ".join(sys.argv[1:]) if sys.argv[1:2] == ["bench"] else "wgpuviewer bench"
    options = resolve_options(args.suite, resolution=resolution, heightmaps=names(args.heightmaps, "--heightmaps"),
                              techniques=names(args.techniques, "--techniques"), angles=angles, frames=args.frames,
                              backend=args.backend, command=command)
    out = Path(args.out)
    if args.from_csv:
        from wgpuviewer.bench.run import rereport

        rereport([Path(p) for p in args.from_csv], out, command)
        print(out / "report.md")
        return 0
    run(options, out, progress=not args.quiet)
    for note in options.notes:
        print(f"note: {note}", file=sys.stderr)
    print(out / "report.md")
    return 0


def cmd_refined_distance(args) -> int:
    from wgpuviewer.studies.refined_distance.run import run

    angles = angle_list(args.angles)
    if angles is not None and not all(0.0 <= a <= 85.0 for a in angles):
        raise UserError(f"--angles {args.angles!r}: expected degrees from 0 to 85")
    heightmaps = names(args.heightmaps, "--heightmaps")
    run(args.suite, Path(args.out), heightmaps=heightmaps, angles=angles, progress=not args.quiet)
    print(f"wrote {Path(args.out) / 'report.md'}")
    return 0


def cmd_info(args) -> int:
    from wgpuviewer.core.gpu import describe_adapters

    print(describe_adapters(args.backend))
    return 0


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="wgpuviewer", description="Relief-mapping techniques on WebGPU: viewer, offscreen renderer, probe."
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    backend_help = f"wgpu backend (default: ${BACKEND_ENV} or auto: hardware first, then software)"

    view = sub.add_parser("view", help="open the interactive viewer (renders a PNG when there is no display)")
    view.add_argument("scene", nargs="?", help="scene TOML (default: the built-in default scene)")
    view.add_argument("--technique", help="technique to start with (default: the scene's)")
    view.add_argument("--backend", choices=BACKEND_CHOICES, help=backend_help)
    view.add_argument("--frames", type=int, help="scripted run: draw this many frames, then exit")
    view.add_argument("--screenshot", help="scripted run: save the last frame to this PNG")
    view.add_argument("--keys", help="scripted run: comma-separated keys to press, one per frame (e.g. 2,3,ArrowRight)")
    view.add_argument("--gui", choices=("glfw", "qt", "auto"), default="glfw",
                      help="window toolkit through rendercanvas (default glfw; qt needs PySide6/PyQt6)")
    view.add_argument("--size", help="window size WIDTHxHEIGHT in logical pixels (default: the saved size, 1280x720)")
    view.set_defaults(func=cmd_view)

    render = sub.add_parser("render", help="render a scene offscreen to PNG or .npy")
    render.add_argument("scene", nargs="?", help="scene TOML (default: the built-in default scene)")
    render.add_argument("-o", "--output", required=True, help="output file: .png (picture) or .npy (raw float32)")
    render.add_argument("--technique", help="technique (default: the scene's)")
    render.add_argument("--size", help=f"WIDTHxHEIGHT (default {DEFAULT_SIZE[0]}x{DEFAULT_SIZE[1]})")
    render.add_argument("--mode", choices=OUTPUT_MODES, default="color", help="what to write")
    render.add_argument("--backend", choices=BACKEND_CHOICES, help=backend_help)
    render.set_defaults(func=cmd_render)

    techniques = sub.add_parser("techniques", help="list techniques, their keys, needed maps and parameters")
    techniques.set_defaults(func=cmd_techniques)

    accuracy = sub.add_parser("accuracy", help="probe each ray-search technique against the float64 reference")
    accuracy.add_argument("--heightmaps", nargs="+", default=["bricks", "bumps", "checker"], help="builtin maps")
    accuracy.add_argument("--texels", type=int, default=256, help="map size (square)")
    accuracy.add_argument("--rays", type=int, default=4096, help="random rays per row")
    accuracy.add_argument("--height-scale", type=float, default=0.05, help="relief depth in UV units")
    accuracy.add_argument("--backend", choices=BACKEND_CHOICES, help=backend_help)
    accuracy.set_defaults(func=cmd_accuracy)

    bench = sub.add_parser("bench", help="speed against error of every technique (results.csv, report.md, plots)")
    bench.add_argument("--out", required=True, help="output folder (results.csv, report.md, *.png)")
    bench.add_argument("--suite", choices=("smoke", "full"), default="full",
                       help="full: real GPUs (1920x1080, all maps and angles); smoke: minutes on a software adapter")
    bench.add_argument("--resolution", help="frame WIDTHxHEIGHT (default: the suite's; full: 1920x1080)")
    bench.add_argument("--heightmaps", help="comma-separated: builtins and/or scikit-image brick,grass,gravel")
    bench.add_argument("--techniques", help="comma-separated technique names (default: all registered)")
    bench.add_argument("--angles", help="comma-separated view angles at the frame centre, degrees (0 to 89)")
    bench.add_argument("--frames", type=int, help="timed frames per configuration (median; default: the suite's)")
    bench.add_argument("--backend", choices=BACKEND_CHOICES, help=backend_help)
    bench.add_argument("--quiet", action="store_true", help="no progress bar")
    bench.add_argument("--from-csv", nargs="+", metavar="CSV",
                       help="measure nothing: write report.md and plots from these results.csv files into --out")
    bench.set_defaults(func=cmd_bench)

    refined = sub.add_parser("refined-distance", help="fetches of the distance tracer on every distance-map "
                             "variant, on the benchmark's views (results.csv, report.md)")
    refined.add_argument("--out", required=True, help="output folder (results.csv, report.md)")
    refined.add_argument("--suite", choices=("smoke", "full"), default="full",
                         help="smoke: two small maps, two angles; full: the benchmark's real maps and wall, 0-80 degrees")
    refined.add_argument("--heightmaps", help="comma-separated: builtins and/or scikit-image brick,grass,gravel")
    refined.add_argument("--angles", help="comma-separated view angles at the frame centre, degrees (0 to 85)")
    refined.add_argument("--quiet", action="store_true", help="no progress bar")
    refined.set_defaults(func=cmd_refined_distance)

    info = sub.add_parser("info", help="list GPU adapters, the chosen one and its relevant features")
    info.add_argument("--backend", choices=BACKEND_CHOICES, help=backend_help)
    info.set_defaults(func=cmd_info)
    return parser


COMMANDS = ("view", "render", "techniques", "accuracy", "bench", "refined-distance", "info")


def main(argv: list[str] | None = None) -> int:
    parser = build_parser()
    argv = list(sys.argv[1:] if argv is None else argv)
    if not argv or (argv[0] not in COMMANDS and argv[0] not in ("-h", "--help")):
        argv = ["view", *argv]  # `wgpuviewer [SCENE] [--technique ...]` means view
    args = parser.parse_args(argv)
    try:
        return args.func(args)
    except UserError as error:
        print(f"wgpuviewer: error: {error}", file=sys.stderr)
        return error.exit_code
    except KeyboardInterrupt:
        return 130
