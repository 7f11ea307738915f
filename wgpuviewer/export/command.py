"""The ``export`` command: ``wgpuviewer export TECHNIQUE [--set NAME=VALUE ...] [--group N] [--uniform-params]
-o OUT.wgsl [--maps HEIGHT [--height-scale S]]`` (``register`` adds it to a parser; ``main`` runs it alone, as
``python -m wgpuviewer.export`` does).

May import: ``wgpuviewer.core``, the technique registry, ``wgpuviewer.relief`` and maptools; never the lab.
"""

from __future__ import annotations

import sys
import tomllib
from pathlib import Path

from wgpuviewer.core.commands import OneLineParser, add_backend_option, command_line, prepare_process, run_command
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.io import output_dir, refuse_directory, write_bytes

from .module import export_wgsl, exportable

DEFAULT_HEIGHT_SCALE = 0.05


def parse_settings(items: list[str] | None) -> dict:
    """``--set NAME=VALUE`` items as parameter values: VALUE read as a TOML value (16, 0.5, true)."""
    settings = {}
    for item in items or ():
        name, sep, text = item.partition("=")
        if not sep or not name.strip():
            raise UserError(f"--set {item!r}: expected NAME=VALUE, e.g. --set layers=32")
        try:
            settings[name.strip()] = tomllib.loads(f"v = {text.strip()}")["v"]
        except tomllib.TOMLDecodeError:
            raise UserError(f"--set {item!r}: {text!r} is not a number or true/false") from None
    return settings


def cmd_export(args) -> int:
    out = Path(args.output)
    if out.suffix.lower() != ".wgsl":
        raise UserError(f"-o {args.output}: expected a .wgsl file name, e.g. {out.with_suffix('.wgsl').name}")
    refuse_directory(out, f"{args.technique}.wgsl")
    export = export_wgsl(args.technique, parse_settings(args.set), args.group, args.uniform_params,
                         getattr(args, "command_line", ""))
    folder = output_dir(out.parent if str(out.parent) else Path("."), "-o")
    if args.maps:
        from wgpuviewer.core.gpu import get_gpu
        from wgpuviewer.core.images import read_height

        from .textures import write_maps

        if not 0.0 <= args.height_scale <= 1.0:
            raise UserError(f"--height-scale {args.height_scale}: expected a relief depth from 0 to 1 UV units")
        height = read_height(args.maps)
        for path in write_maps(get_gpu(args.backend, quiet=True), export, height, args.height_scale, folder,
                               Path(args.maps).stem):
            print(path)
    write_bytes(out, export.code.encode())
    print(out)
    return 0


def register(sub) -> None:
    """``export``'s parser in a subcommand set."""
    parser = sub.add_parser("export", help="a ray-search technique as one self-contained WGSL module "
                            "(relief_trace) for your own renderer, and the maps it binds")
    add_arguments(parser)


def add_arguments(parser) -> None:
    parser.add_argument("technique", help=f"the technique: {', '.join(exportable())}")
    parser.add_argument("-o", "--output", required=True, help="the module to write, OUT.wgsl")
    parser.add_argument("--set", action="append", metavar="NAME=VALUE",
                        help="a parameter's value, compiled in as a constant (repeatable; `wgpuviewer techniques` "
                        "lists them; the defaults for the rest)")
    parser.add_argument("--group", type=int, default=1, help="the bind group of its bindings (default %(default)s)")
    parser.add_argument("--uniform-params", action="store_true",
                        help="keep the parameters in the uniform (ReliefParams) instead of constants")
    parser.add_argument("--maps", metavar="HEIGHT",
                        help="also write the textures it binds, built from this height map, next to OUT: "
                        "STEM.SLOT.texture.npz each and STEM.relief_params.json (the uniform's values)")
    parser.add_argument("--height-scale", type=float, default=DEFAULT_HEIGHT_SCALE,
                        help="relief depth in UV units the maps are built for, with --maps (default %(default)s)")
    add_backend_option(parser)
    parser.set_defaults(func=cmd_export)


def main(argv: list[str] | None = None) -> int:
    """``export`` alone (exit codes as every command: 0 ok, 2 a user error, 3 an internal error)."""
    prepare_process("wgpuviewer")
    given = list(sys.argv[1:] if argv is None else argv)

    def command() -> int:
        parser = OneLineParser(prog="wgpuviewer export", description="A ray-search technique as one WGSL module.")
        add_arguments(parser)
        args = parser.parse_args(given)
        args.command_line = command_line("wgpuviewer export", given)
        return args.func(args)

    try:
        return run_command("wgpuviewer", command)
    except SystemExit as exit_:
        return int(exit_.code or 0)
