"""Command line: ``wgpuviewer view|render|techniques|filters|accuracy|info`` here, and the measuring commands:
``bench`` and every study under ``wgpuviewer/studies/`` (found by the harness, each registering itself)."""

from __future__ import annotations

import argparse
import math
import os
import sys
from pathlib import Path

from wgpuviewer.core.cli import (
    OneLineParser,
    add_backend_option,
    command_line,
    parse_size,
    prepare_process,
    run_command,
    terminal_progress,
)
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import refuse_directory

DEFAULT_SIZE = (1280, 720)
MATERIAL_HELP = ("a material folder (ambientCG, Poly Haven or albedo/normal/height names) shown on the scene's "
                 "first plane; without SCENE, the default scene's")


def load_scene_arg(path: str | None):
    from .scene import default_scene_path, load_scene

    return load_scene(Path(path) if path else default_scene_path())


def pick_technique(scene, name: str | None) -> str:
    from wgpuviewer.relief.techniques import get_technique

    return get_technique(name or scene.technique, "--technique").name


def pick_filtering(args) -> dict:
    """DrawConfig's filter and derivatives from ``--filter`` / ``--derivatives`` (checked against the registry)."""
    from wgpuviewer.relief.filters import get_derivatives, get_filter

    return {"filter": get_filter(args.filter, "--filter").name,
            "derivatives": get_derivatives(args.derivatives, "--derivatives").name}


def has_display() -> bool:
    if sys.platform.startswith("linux"):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


def render_to(out: Path, scene, technique: str, size: tuple[int, int], mode: str, backend: str | None,
              filtering: dict) -> None:
    """Render ``scene`` offscreen into ``out`` (.png or .npy), the maps it needs built first with a progress bar;
    ``filtering``: the texture filter and derivative source (``pick_filtering``). A frame too large for the adapter
    is refused (naming ``--size``) before any map is built."""
    from wgpuviewer.core.gpu import get_gpu
    from wgpuviewer.relief.output import save_output
    from wgpuviewer.relief.renderer import Renderer, check_frame_size

    gpu = get_gpu(backend)
    check_frame_size(gpu, size, "--size")
    renderer = Renderer(scene, gpu)
    with terminal_progress(f"maps for {technique}") as progress:
        renderer.prepare(technique, progress)
    image = renderer.render(renderer.config(technique, **filtering), size, mode=mode, size_name="--size")
    save_output(out, image, mode)


def cmd_render(args) -> int:
    from wgpuviewer.relief.output import OUTPUT_SUFFIXES

    out = Path(args.output)
    refuse_directory(out, "render.png")
    if out.suffix.lower() not in OUTPUT_SUFFIXES:
        raise UserError(f"-o {out}: unknown output type {out.suffix!r}; use .png (image) or .npy (raw float32 data)")
    scene = scene_from_args(args)
    technique = pick_technique(scene, args.technique)
    size = parse_size(args.size) if args.size else DEFAULT_SIZE
    render_to(out, scene, technique, size, args.mode, args.backend, pick_filtering(args))
    print(out)
    return 0


def scene_from_args(args, fallback: str | None = None):
    """The scene of ``args.scene`` (default: the built-in one, or ``fallback``), with ``--material DIR`` shown on
    its first plane."""
    from .scene import with_folder_material

    scene = load_scene_arg(args.scene or fallback)
    return with_folder_material(scene, Path(args.material)) if args.material else scene


def cmd_view(args) -> int:
    from wgpuviewer.viewer.settings import load_settings

    scripted = args.frames is not None or bool(args.screenshot) or bool(args.keys)
    settings, _warnings = load_settings()  # corrupt/outdated file: defaults + a warning on stderr
    technique_arg = args.technique
    window = has_display()
    last = settings.last_scene if window and not scripted and args.scene is None and not args.material else ""
    scene = None
    if last:  # interactive runs continue where the last one ended
        try:
            scene = scene_from_args(args, last)
            print(f"opening the last scene {last} (give a SCENE to open another)", file=sys.stderr)
        except UserError as error:
            print(f"wgpuviewer: warning: the last scene cannot be opened ({error}); opening the default scene",
                  file=sys.stderr)
            last = ""
    if scene is None:
        scene = scene_from_args(args)
    if last and technique_arg is None and settings.last_technique in scene.techniques:
        technique_arg = settings.last_technique
    technique = pick_technique(scene, technique_arg)
    filtering = pick_filtering(args)
    size = parse_size(args.size) if args.size else None
    if not window:
        out = Path("out") / f"{Path(scene.path).stem if scene.path else 'scene'}_{technique}.png"
        print(f"no display found (DISPLAY/WAYLAND_DISPLAY unset): rendering the scene to {out} instead")
        render_to(out, scene, technique, size or DEFAULT_SIZE, "color", args.backend, filtering)
        print(out)
        return 0
    from wgpuviewer.viewer.app import run_viewer

    keys = [k for k in args.keys.split(",") if k] if args.keys else []
    return run_viewer(
        scene, technique, backend=args.backend, frames=args.frames, screenshot=args.screenshot, keys=keys,
        gui=args.gui, settings=settings, size=size, **filtering,
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


def cmd_filters(args) -> int:
    from wgpuviewer.relief.filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER, DERIVATIVE_SOURCES, FILTERS

    for f in FILTERS.values():
        default = "  (default)" if f.name == DEFAULT_FILTER else ""
        print(f"{f.name:<13} reads: {f.cost}{default}")
        print(f"   {f.description}")
        for p in f.params:
            print(f"   - {p.name} ({p.kind.__name__}, default {p.default}, [{p.min:g}..{p.max:g}]): {p.doc}")
    print("\nderivative sources (--derivatives):")
    for d in DERIVATIVE_SOURCES.values():
        default = "  (default)" if d.name == DEFAULT_DERIVATIVES else ""
        print(f"{d.name:<13} {d.description}{default}")
    return 0


def cmd_accuracy(args) -> int:
    if args.rays < 1:
        raise UserError(f"--rays {args.rays}: expected at least 1 ray")
    if not (math.isfinite(args.height_scale) and 0 < args.height_scale <= 1):
        raise UserError(f"--height-scale {args.height_scale}: expected a relief depth in (0, 1] UV units")
    if args.texels < 1:
        raise UserError(f"--texels {args.texels}: expected at least 1 texel")
    if args.doc:
        refuse_directory(args.doc, "accuracy.md")
    from tqdm import tqdm

    from wgpuviewer.core.io import write_bytes
    from wgpuviewer.relief.accuracy import DEFAULT_ANGLES, DEFAULT_SETTINGS, markdown_report, run, table

    from .textures import BUILTINS, builtin_height

    for name in args.heightmaps:
        if name not in BUILTINS:
            raise UserError(f"--heightmaps: unknown builtin {name!r}; expected some of {', '.join(BUILTINS)}")
    maps = {name: builtin_height(name, (args.texels, args.texels)) for name in args.heightmaps}
    total = len(maps) * len(DEFAULT_SETTINGS) * len(DEFAULT_ANGLES)
    from wgpuviewer.core.gpu import get_gpu

    gpu = get_gpu(args.backend)
    with tqdm(total=total, desc="probe vs reference", file=sys.stderr, leave=False) as bar:
        if args.doc:
            measured = run(maps, height_scale=args.height_scale, rays=args.rays, backend=args.backend,
                           progress=bar.update)
        else:
            text = table(maps, height_scale=args.height_scale, rays=args.rays, backend=args.backend,
                         progress=bar.update)
    if args.doc:
        report = markdown_report(measured, command=args.command_line, adapter=gpu.summary)
        write_bytes(args.doc, report.encode("utf-8"))
        print(args.doc)
        return 0
    print(f"Adapter: {gpu.summary}; height_scale {args.height_scale}; {args.rays} random rays per row; "
          f"{args.texels}x{args.texels} maps; errors over rays that were not capped.\n")
    print(text)
    return 0


def cmd_info(args) -> int:
    from wgpuviewer.core.gpu import describe_adapters

    print(describe_adapters(args.backend))
    return 0


def add_filter_options(parser) -> None:
    from wgpuviewer.relief.filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER

    parser.add_argument("--filter", default=DEFAULT_FILTER,
                        help=f"texture filter for the albedo and normal lookups (default {DEFAULT_FILTER}; "
                        "`wgpuviewer filters` lists them)")
    parser.add_argument("--derivatives", default=DEFAULT_DERIVATIVES,
                        help=f"derivative source the filter's footprint comes from: uv, displaced, analytic "
                        f"(default {DEFAULT_DERIVATIVES})")


def measurement_commands() -> list:
    """bench, then every study folder's ``STUDY`` (the harness finds them)."""
    from wgpuviewer.bench import STUDY as BENCH
    from wgpuviewer.harness.study import discover

    return [BENCH, *discover()]


def build_parser() -> tuple[argparse.ArgumentParser, tuple[str, ...]]:
    """The parser and the names of its commands."""
    from wgpuviewer.harness.study import register
    from wgpuviewer.relief.output import OUTPUT_MODES

    parser = OneLineParser(
        prog="wgpuviewer", description="Relief-mapping techniques on WebGPU: viewer, offscreen renderer, probe."
    )
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    view = sub.add_parser("view", help="open the interactive viewer (renders a PNG when there is no display)")
    view.add_argument("scene", nargs="?", help="scene TOML (default: the built-in default scene)")
    view.add_argument("--technique", help="technique to start with (default: the scene's)")
    add_backend_option(view)
    view.add_argument("--frames", type=int, help="scripted run: draw this many frames, then exit")
    view.add_argument("--screenshot", help="scripted run: save the last frame to this PNG")
    view.add_argument("--keys", help="scripted run: comma-separated keys to press, one per frame (e.g. 2,3,ArrowRight)")
    view.add_argument("--gui", choices=("glfw", "qt", "auto"), default="glfw",
                      help="window toolkit through rendercanvas (default glfw; qt needs PySide6/PyQt6)")
    view.add_argument("--size", help="window size WIDTHxHEIGHT in logical pixels (default: the saved size, 1280x720)")
    view.add_argument("--material", metavar="DIR", help=MATERIAL_HELP)
    add_filter_options(view)
    view.set_defaults(func=cmd_view)

    render = sub.add_parser("render", help="render a scene offscreen to PNG or .npy")
    render.add_argument("scene", nargs="?", help="scene TOML (default: the built-in default scene)")
    render.add_argument("-o", "--output", required=True, help="output file: .png (picture) or .npy (raw float32)")
    render.add_argument("--technique", help="technique (default: the scene's)")
    render.add_argument("--size", help=f"WIDTHxHEIGHT (default {DEFAULT_SIZE[0]}x{DEFAULT_SIZE[1]})")
    render.add_argument("--mode", choices=OUTPUT_MODES, default="color", help="what to write")
    add_backend_option(render)
    render.add_argument("--material", metavar="DIR", help=MATERIAL_HELP)
    add_filter_options(render)
    render.set_defaults(func=cmd_render)

    techniques = sub.add_parser("techniques", help="list techniques, their keys, needed maps and parameters")
    techniques.set_defaults(func=cmd_techniques)

    filters = sub.add_parser("filters", help="list texture filters, their parameters and the derivative sources")
    filters.set_defaults(func=cmd_filters)

    accuracy = sub.add_parser("accuracy", help="probe each ray-search technique against the float64 reference")
    accuracy.add_argument("--heightmaps", nargs="+", default=["bricks", "bumps", "checker"], help="builtin maps")
    accuracy.add_argument("--texels", type=int, default=256, help="map size (square)")
    accuracy.add_argument("--rays", type=int, default=4096, help="random rays per row")
    accuracy.add_argument("--height-scale", type=float, default=0.05, help="relief depth in UV units")
    add_backend_option(accuracy)
    accuracy.add_argument("--doc", metavar="PATH",
                          help="write the markdown report (docs/accuracy.md) to PATH instead of printing the table")
    accuracy.set_defaults(func=cmd_accuracy)

    for study in measurement_commands():
        register(sub, study)

    info = sub.add_parser("info", help="list GPU adapters, the chosen one and its relevant features")
    add_backend_option(info)
    info.set_defaults(func=cmd_info)
    return parser, tuple(sub.choices)


def main(argv: list[str] | None = None) -> int:
    """Exit codes (wgpuviewer.core.cli): 0 ok, 1 a check failed, 2 a user error, 3 an internal error."""
    prepare_process("wgpuviewer")  # before any GPU driver loads
    given = list(sys.argv[1:] if argv is None else argv)

    def command() -> int:
        parser, commands = build_parser()
        words = given if given and (given[0] in commands or given[0] in ("-h", "--help")) else ["view", *given]
        args = parser.parse_args(words)  # `wgpuviewer [SCENE] [--technique ...]` means view
        args.command_line = command_line("wgpuviewer", words)  # what the reports record
        return args.func(args)

    try:
        return run_command("wgpuviewer", command)
    except SystemExit as exit_:  # argparse: --help (0) and usage errors (2, one line)
        return int(exit_.code or 0)
