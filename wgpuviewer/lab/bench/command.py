"""``wgpuviewer bench``: its options and how they become a run (or a report regenerated from results files)."""

from __future__ import annotations

import sys
from pathlib import Path

from wgpuviewer.core.commands import comma_list, comma_numbers, parse_size
from wgpuviewer.core.errors import UserError
from wgpuviewer.lab.harness.study import add_measurement_options


class Bench:
    name = "bench"
    help = "speed against error of every technique (results.csv, report.md, plots)"

    def add_arguments(self, parser) -> None:
        add_measurement_options(
            parser, "output folder (results.csv, report.md, *.png)",
            "full: real GPUs (1920x1080, all maps and angles); smoke: minutes on a software adapter")
        parser.add_argument("--resolution", help="frame WIDTHxHEIGHT (default: the suite's; full: 1920x1080)")
        parser.add_argument("--heightmaps", help="comma-separated: builtins and/or scikit-image brick,grass,gravel")
        parser.add_argument("--techniques", help="comma-separated technique names (default: all registered)")
        parser.add_argument("--angles", help="comma-separated view angles at the frame centre, degrees (0 to 89)")
        parser.add_argument("--frames", type=int, help="timed frames per configuration (median; default: the suite's)")
        parser.add_argument("--simd-tile",
                            help="WIDTHxHEIGHT pixels of the SIMD group for the fetches_simd cost (default 8x4)")
        parser.add_argument("--from-csv", nargs="+", metavar="CSV",
                            help="measure nothing: write report.md and plots from these results.csv files into --out")

    def options(self, args) -> dict:
        """What ``run`` takes: the run's options (each checked) or the results files to report again."""
        from .run import resolve_options

        def size(text, option):
            return parse_size(text, option) if text else None

        options = resolve_options(
            args.suite, resolution=size(args.resolution, "--resolution"),
            heightmaps=comma_list(args.heightmaps, "--heightmaps"),
            techniques=comma_list(args.techniques, "--techniques"),
            angles=comma_numbers(args.angles, "--angles", "0,45,80"), frames=args.frames, backend=args.backend,
            command=args.command_line, simd_tile=size(args.simd_tile, "--simd-tile"))
        from_csv = [Path(p) for p in args.from_csv or ()]
        for path in from_csv:
            if not path.is_file():
                raise UserError(f"--from-csv {path}: no such file; give the results.csv of earlier runs")
        return {"options": options, "from_csv": from_csv, "progress": not args.quiet}

    def run(self, checked: dict, out: Path) -> int:
        from .run import rereport, run

        options = checked["options"]
        if checked["from_csv"]:
            rereport(checked["from_csv"], out, options.command)
        else:
            run(options, out, progress=checked["progress"])
            for note in options.notes:
                print(f"note: {note}", file=sys.stderr)
        print(out / "report.md")
        return 0


STUDY = Bench()
