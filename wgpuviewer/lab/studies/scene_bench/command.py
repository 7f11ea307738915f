"""``wgpuviewer scene-bench``: the command's options."""

from __future__ import annotations

from wgpuviewer.lab.harness.study import StudyCommand


class SceneBench(StudyCommand):
    def add_options(self, parser) -> None:
        parser.add_argument("scenes", nargs="*", metavar="SCENE",
                            help="scene files, or the default scenes by name: showcase, default, photos, curved "
                                 "(default: the suite's)")
        parser.add_argument("--size", help="frame WxH (default: the suite's; smoke 64x36, full 384x216)")

    def options(self, args) -> dict:
        """``run.run``'s keyword arguments, each option checked (no file made, no GPU started)."""
        from wgpuviewer.core.commands import parse_size

        from .scenes import check_scene

        for name in args.scenes:
            check_scene(name)
        size = parse_size(args.size) if args.size is not None else None
        return {**self.shared_options(args), "scene_names": tuple(args.scenes) or None, "size": size}


STUDY = SceneBench(
    "scene-bench", "whole scenes in screen pixels and FLIP: per scene, view and technique configuration, the hit "
    "error in pixels, FLIP and PSNR against the exact tracer, fetches and time against basic (results.csv, "
    "report.md, plots)",
    "output folder (results.csv, report.md, pareto.png, worst_pixels.png)",
    "smoke: the default scene, one view, 64x36, pom 8 and relief (seconds); full: the showcase, the default, "
    "photographs and curved scenes, near, far and grazing views, 384x216, pom 8-32, auto, contact, relief, steep")
