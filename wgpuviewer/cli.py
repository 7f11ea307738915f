"""Command line: ``wgpuviewer view|render|warm|techniques|filters|info`` here, and the measuring commands:
``bench`` and every study under ``wgpuviewer/lab/studies/`` (found by the harness, each registering itself)."""

from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path

from wgpuviewer.core.commands import (
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
from wgpuviewer.export.command import register as register_export

from .cli_render import api_errors, prepare_render, render_orbit, save_render

DEFAULT_SIZE = (1280, 720)
#: What `render`'s --height-scale, --uv-scale and --view-angle are about (wgpuviewer.api.subject).
SUBJECT = "the scene's first plane (where --material shows its folder), or its first object when it has no plane"
SUBJECT_MATERIAL = f"the material of {SUBJECT}"
VIEW_ANGLE_HELP = (f"place the camera so that its view meets the surface of {SUBJECT} (a box: its top face; a quad: "
                   "its front) at DEG degrees from the surface normal: 0 looks straight down onto it, 90 would graze "
                   "it (0 <= DEG < 90). The camera looks at the target (--target, or the scene camera's) from the "
                   "scene camera's distance to it, on the side of the surface the scene camera sees it from; "
                   "not with --camera")
MATERIAL_HELP = ("a material folder (ambientCG, Poly Haven or albedo/normal/height names) shown on the scene's "
                 "first plane; without SCENE, the default scene's")


def load_scene_arg(path: str | None):
    from .scene import default_scene_path, load_scene

    return load_scene(Path(path) if path else default_scene_path())


def pick_technique(scene, name: str | None) -> str:
    from wgpuviewer.techniques import get_technique

    return get_technique(name or scene.technique, "--technique").name


def pick_filtering(args) -> dict:
    """The viewer's filter and derivatives from ``--filter`` / ``--derivatives`` (checked against the registry),
    and its self-shadowing override from ``--shadows`` (None: each material's own)."""
    from wgpuviewer.relief.filters import get_derivatives, get_filter

    return {"filter": get_filter(args.filter, "--filter").name,
            "derivatives": get_derivatives(args.derivatives, "--derivatives").name, "shadows": args.shadows}


def has_display() -> bool:
    if sys.platform.startswith("linux"):
        return bool(os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY"))
    return True


def cmd_render(args) -> int:
    from wgpuviewer.relief.output import OUTPUT_SUFFIXES

    out = Path(args.output)
    refuse_directory(out, "render.png")
    size = parse_size(args.size) if args.size else DEFAULT_SIZE
    if args.alpha and args.orbit is not None:
        raise UserError(f"--alpha: a turntable ({out.suffix}) has no alpha; drop --alpha or render single frames to "
                        ".png")
    if args.orbit is not None:
        from wgpuviewer.relief.turntable import check_turntable

        check_turntable(out, args.orbit, size)
    elif out.suffix.lower() not in OUTPUT_SUFFIXES:
        raise UserError(f"-o {out}: unknown output type {out.suffix!r}; use .png (image) or .npy (raw float32 data), "
                        "or .gif or .mp4 with --orbit N")
    scene = scene_from_args(args)
    with api_errors():
        prepared = prepare_render(args, scene, size)
        if args.orbit is not None:
            render_orbit(out, prepared, args.mode, args.orbit)
        else:
            save_render(out, prepared, args.mode, args.alpha)
    print(out)
    return 0


def scene_from_args(args, fallback: str | None = None):
    """The scene of ``args.scene`` (default: the built-in one, or ``fallback``), with ``--material DIR`` shown on
    its first plane."""
    from .scene import with_folder_material

    scene = load_scene_arg(args.scene or fallback)
    return with_folder_material(scene, Path(args.material)) if args.material else scene


def cmd_view(args) -> int:
    from wgpuviewer.viewer.runner import scripted_frames
    from wgpuviewer.viewer.settings import load_settings

    keys = [k for k in args.keys.split(",") if k] if args.keys else []
    if args.keys is not None and not keys:
        raise UserError(f"--keys {args.keys!r}: no keys given; expected comma-separated keys, e.g. 2,3,ArrowRight")
    # The script is checked first: before the scene loads, the GPU starts or a display is looked for.
    scripted = scripted_frames(args.frames, args.screenshot, keys) is not None
    window = has_display()
    if keys and not window:
        raise UserError(f"--keys {args.keys}: no display (DISPLAY/WAYLAND_DISPLAY unset) to play them in; run under "
                        "one (e.g. xvfb-run -a wgpuviewer view ...), or drop --keys for an offscreen --screenshot")
    settings, _warnings = load_settings()  # corrupt/outdated file: defaults + a warning on stderr
    technique_arg = args.technique
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
        return view_offscreen(args, scene, technique, filtering, size or (settings.width, settings.height))
    from wgpuviewer.viewer.app import run_viewer

    return run_viewer(
        scene, technique, backend=args.backend, frames=args.frames, screenshot=args.screenshot, keys=keys,
        gui=args.gui, settings=settings, size=size, **filtering,
    )


def view_offscreen(args, scene, technique: str, filtering: dict, size: tuple[int, int]) -> int:
    """``view`` without a display: the scene the window would show, rendered offscreen (``api.prepare``) at the
    window's size into ``--screenshot`` (without the HUD), or into out/SCENE_TECHNIQUE.png when no screenshot was
    asked for."""
    from wgpuviewer.api import prepare

    if args.screenshot:
        out = Path(args.screenshot)
        print(f"no display found (DISPLAY/WAYLAND_DISPLAY unset): writing {out} as an offscreen render of the scene "
              "(no HUD)")
    else:
        out = Path("out") / f"{Path(scene.path).stem if scene.path else 'scene'}_{technique}.png"
        print(f"no display found (DISPLAY/WAYLAND_DISPLAY unset): rendering the scene to {out} instead")
    with api_errors():
        save_render(out, prepare(scene, technique, size, backend=args.backend, keep=False, **filtering), "color")
    print(out)
    return 0


def cmd_techniques(args) -> int:
    from wgpuviewer.techniques import TECHNIQUES

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


def cmd_info(args) -> int:
    from wgpuviewer.core.gpu import describe_adapters

    print(describe_adapters(args.backend))
    return 0


def cmd_warm(args) -> int:
    """Build every map the chosen techniques need on the scene (or a material folder) into the map cache; one line
    per technique, exit 1 when one could not be built."""
    from maptools.cache import cache_dir
    from wgpuviewer.core.gpu import get_gpu
    from wgpuviewer.relief.warm import warm
    from wgpuviewer.techniques import TECHNIQUES, get_technique

    if args.scene and Path(args.scene).is_dir():  # SCENE|DIR: a folder is a material folder on the default scene
        if args.material:
            raise UserError(f"warm {args.scene}: a folder is a material folder; give it or --material, not both")
        args.scene, args.material = None, args.scene
    scene = scene_from_args(args)
    if args.techniques is None:
        techniques = scene.techniques
    elif args.techniques.strip() == "all":
        techniques = tuple(TECHNIQUES)
    else:
        names = [n.strip() for n in args.techniques.split(",") if n.strip()]
        if not names:
            raise UserError(f"--techniques {args.techniques!r}: expected technique names, e.g. pom,distance, or all")
        techniques = tuple(dict.fromkeys(get_technique(n, "--techniques").name for n in names))
    gpu = get_gpu(args.backend)
    failed = 0
    for technique in techniques:
        with terminal_progress(f"maps for {technique}") as progress:
            result = warm(scene, gpu, technique, progress)
        failed += bool(result.error)
        print(result.summary)
    print(f"map cache: {cache_dir()}")
    return 1 if failed else 0


def add_filter_options(parser) -> None:
    from wgpuviewer.relief.filters import DEFAULT_DERIVATIVES, DEFAULT_FILTER
    from wgpuviewer.scene import SHADOW_MODES

    parser.add_argument("--filter", default=DEFAULT_FILTER,
                        help=f"texture filter for the albedo and normal lookups (default {DEFAULT_FILTER}; "
                        "`wgpuviewer filters` lists them)")
    parser.add_argument("--derivatives", default=DEFAULT_DERIVATIVES,
                        help=f"derivative source the filter's footprint comes from: uv, displaced, analytic "
                        f"(default {DEFAULT_DERIVATIVES})")
    parser.add_argument("--shadows", choices=SHADOW_MODES,
                        help="self-shadowing of every material's relief, overriding the materials' `shadows` "
                        "(default: each material's own)")


def measurement_commands() -> list:
    """bench, then every study folder's ``STUDY`` (the harness finds them)."""
    from wgpuviewer.lab.bench import STUDY as BENCH
    from wgpuviewer.lab.harness.study import discover

    return [BENCH, *discover()]


def add_view_command(sub) -> None:
    """``view``'s parser."""
    view = sub.add_parser("view", help="open the interactive viewer (renders a PNG when there is no display)")
    view.add_argument("scene", nargs="?", help="scene TOML (default: the built-in default scene)")
    view.add_argument("--technique", help="technique to start with (default: the scene's)")
    add_backend_option(view)
    view.add_argument("--frames", type=int, help="scripted run: draw this many frames, then exit")
    view.add_argument("--screenshot", metavar="PATH",
                      help="scripted run: save the last frame to this PNG (no display: an offscreen render of the "
                      "scene, without the HUD)")
    view.add_argument("--keys", help="scripted run: comma-separated keys, one per frame (e.g. 2,3,ArrowRight), and the "
                      "fly keys held for seconds of motion, W:0.5 (W A S D Q E, played at 30 frames per second: "
                      "15 frames); needs a display")
    view.add_argument("--gui", choices=("glfw", "qt", "auto"), default="glfw",
                      help="window toolkit through rendercanvas (default glfw; qt needs PySide6/PyQt6)")
    view.add_argument("--size", help="window size WIDTHxHEIGHT in logical pixels (default: the saved size, 1280x720)")
    view.add_argument("--material", metavar="DIR", help=MATERIAL_HELP)
    add_filter_options(view)
    view.set_defaults(func=cmd_view)


def add_render_command(sub) -> None:
    """``render``'s parser."""
    from wgpuviewer.relief.output import MODE_DESCRIPTIONS, OUTPUT_MODES

    render = sub.add_parser("render", help="render a scene offscreen to PNG or .npy")
    render.add_argument("scene", nargs="?", help="scene TOML (default: the built-in default scene)")
    render.add_argument("-o", "--output", required=True,
                        help="output file: .png (picture) or .npy (raw float32); .gif or .mp4 with --orbit")
    render.add_argument("--orbit", type=int, metavar="N",
                        help="a turntable: N frames (2 to 3600) of one full turn of the camera about the vertical "
                        "axis through its target, written to -o OUT.gif or OUT.mp4 at 25 frames per second "
                        "(pip install 'wgpuviewer[turntable]')")
    render.add_argument("--technique", help="technique (default: the scene's)")
    render.add_argument("--size", help=f"WIDTHxHEIGHT (default {DEFAULT_SIZE[0]}x{DEFAULT_SIZE[1]})")
    render.add_argument("--mode", choices=OUTPUT_MODES, default="color", metavar="MODE",
                        help=f"what to write (default %(default)s): "
                        f"{', '.join(f'{m} ({what})' for m, what in MODE_DESCRIPTIONS.items())}. A .npy holds the "
                        "raw float32 values, NaN where nothing was drawn")
    render.add_argument("--alpha", action="store_true",
                        help="transparent background: an RGBA PNG whose alpha is 0 where nothing was drawn (color "
                        "and albedo .npy get that as a fourth channel)")
    add_backend_option(render)
    render.add_argument("--material", metavar="DIR", help=MATERIAL_HELP)
    render.add_argument("--camera", metavar="X,Y,Z",
                        help="camera position (default: the scene camera's); a value starting with '-' needs '=': "
                        "--camera=-1,0.5,2")
    render.add_argument("--target", metavar="X,Y,Z", help="the point the camera looks at (default: the scene camera's)")
    render.add_argument("--fov", type=float, metavar="DEG",
                        help="vertical field of view in degrees, above 1 and below 179 (default: the scene camera's)")
    render.add_argument("--view-angle", type=float, metavar="DEG", help=VIEW_ANGLE_HELP)
    render.add_argument("--height-scale", type=float, metavar="H",
                        help=f"relief depth in UV units, 0 to 1, of {SUBJECT_MATERIAL} (default: the material's)")
    render.add_argument("--uv-scale", metavar="S|U,V",
                        help=f"texture repeats across the object for {SUBJECT_MATERIAL}: one number for both "
                        "directions or U,V (default: the material's)")
    add_filter_options(render)
    render.set_defaults(func=cmd_render)


def build_parser() -> tuple[argparse.ArgumentParser, tuple[str, ...]]:
    """The parser and the names of its commands."""
    from wgpuviewer.lab.docs import register as register_docs
    from wgpuviewer.lab.harness.study import register

    parser = OneLineParser(
        prog="wgpuviewer", description="Relief-mapping techniques on WebGPU: viewer, offscreen renderer, probe."
    )
    parser.add_argument("--version", action="version", version=f"%(prog)s {installed_version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    add_view_command(sub)
    add_render_command(sub)
    register_export(sub)

    warm_ = sub.add_parser("warm", help="build every map a scene's techniques need into the map cache, now")
    warm_.add_argument("scene", nargs="?", metavar="SCENE|DIR",
                       help="scene TOML, or a material folder shown on the default scene (default: the default scene)")
    warm_.add_argument("--techniques", metavar="NAMES",
                       help="comma-separated techniques, or all (default: the scene's techniques)")
    warm_.add_argument("--material", metavar="DIR", help=MATERIAL_HELP)
    add_backend_option(warm_)
    warm_.set_defaults(func=cmd_warm)

    techniques = sub.add_parser("techniques", help="list techniques, their keys, needed maps and parameters")
    techniques.set_defaults(func=cmd_techniques)

    filters = sub.add_parser("filters", help="list texture filters, their parameters and the derivative sources")
    filters.set_defaults(func=cmd_filters)

    for study in measurement_commands():
        register(sub, study)
    register_docs(sub)  # the lab's `wgpuviewer docs`: the generated blocks of README.md and docs/*.md

    info = sub.add_parser("info", help="list GPU adapters, the chosen one and its relevant features")
    add_backend_option(info)
    info.set_defaults(func=cmd_info)
    return parser, tuple(sub.choices)


def installed_version() -> str:
    """The installed wgpuviewer distribution's version (package metadata)."""
    from importlib.metadata import PackageNotFoundError, version

    try:
        return version("wgpuviewer")
    except PackageNotFoundError:
        return "(not installed: pip install -e . in the checkout)"


def main(argv: list[str] | None = None) -> int:
    """Exit codes (wgpuviewer.core.commands): 0 ok, 1 a check failed, 2 a user error, 3 an internal error."""
    prepare_process("wgpuviewer")  # before any GPU driver loads
    given = list(sys.argv[1:] if argv is None else argv)

    def command() -> int:
        parser, commands = build_parser()
        words = given if given and (given[0] in commands or given[0] in ("-h", "--help", "--version")) \
            else ["view", *given]
        args = parser.parse_args(words)  # `wgpuviewer [SCENE] [--technique ...]` means view
        args.command_line = command_line("wgpuviewer", words)  # what the reports record
        return args.func(args)

    try:
        return run_command("wgpuviewer", command)
    except SystemExit as exit_:  # argparse: --help (0) and usage errors (2, one line)
        return int(exit_.code or 0)
