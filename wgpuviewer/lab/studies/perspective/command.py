"""``wgpuviewer perspective``: the command (beside the shared options: ``--threads-only``, which times only the
paper's parallel forms on real threads, ``threads_report.run_threads``)."""

from __future__ import annotations

from wgpuviewer.lab.harness.study import StudyCommand


class Perspective(StudyCommand):
    def add_options(self, parser) -> None:
        parser.add_argument("--threads-only", action="store_true",
                            help="time only the parallel forms on 1, 2 and all threads (threads.csv, report.md)")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments (argparse has checked the suite); numba is there for the compiled loops."""
        from .compiled import numba_module

        numba_module()
        return {**self.shared_options(args), "threads_only": args.threads_only}

    def run(self, options: dict, out) -> int:
        options = dict(options)
        if options.pop("threads_only"):
            from .threads_only import run_threads

            run_threads(out=out, **options)
            print(out / "report.md")
            return 0
        return super().run(options, out)


STUDY = Perspective(
    "perspective", "perspective-correct texturing study (Romanyuk & Dudnyk): speed and float error of Heckbert's "
    "direct, incremental and parallel forms", "output folder (results.csv, report.md, *.png)",
    "full: every sweep, 4K frames (minutes on a software adapter); smoke: seconds, for CI")
