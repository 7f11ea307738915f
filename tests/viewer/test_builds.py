"""The map-build orchestration of the A/B sides without a GPU: a stand-in renderer whose maps are 'built' by
``prepare``."""

from __future__ import annotations

import threading

from wgpuviewer.core.errors import InputError
from wgpuviewer.viewer.builds import Builds


class FakeRenderer:
    def __init__(self, built=(), bad=(), gate: threading.Event | None = None):
        self.built, self.bad, self.gate = set(built), set(bad), gate
        self.prepared: list[str] = []

    def missing(self, name):
        return [] if name in self.built else [f"{name} maps"]

    def prepare(self, name, progress=None):
        if self.gate is not None:
            self.gate.wait(10)
        self.prepared.append(name)
        if name in self.bad:
            raise InputError(f"{name}: damaged texture")
        self.built.add(name)


def builds_for(renderer, background):
    shown = {"A": "normal", "B": "normal"}
    problems: list[str] = []
    builds = Builds(renderer, background, show=shown.__setitem__, problem=problems.append, shown=shown.__getitem__)
    return builds, shown, problems


def test_a_ready_technique_shows_at_once_and_a_missing_one_is_built_in_place_without_background():
    renderer = FakeRenderer(built={"normal", "parallax"})
    builds, shown, problems = builds_for(renderer, background=False)
    builds.request("A", "parallax")
    assert shown["A"] == "parallax" and renderer.prepared == []
    builds.request("B", "pom")
    assert shown == {"A": "parallax", "B": "pom"} and renderer.prepared == ["pom"] and builds.current is None
    builds.request("A", "relief")
    renderer.bad.add("cone")
    builds.request("A", "cone")
    assert shown["A"] == "relief" and problems == ["cone: damaged texture"]


def test_a_background_build_shows_its_technique_when_done_if_still_wanted():
    gate = threading.Event()
    renderer = FakeRenderer(built={"normal"}, gate=gate)
    builds, shown, problems = builds_for(renderer, background=True)
    builds.request("A", "pom")
    assert builds.current is not None and shown["A"] == "normal"  # the side keeps its technique meanwhile
    builds.request("B", "relief")  # one build at a time: relief waits
    builds.poll()
    assert shown == {"A": "normal", "B": "normal"}
    gate.set()
    assert builds.current.wait(10)
    builds.poll()  # pom is shown; relief, asked for meanwhile, starts
    assert shown["A"] == "pom" and builds.current is not None and builds.current.technique == "relief"
    assert builds.current.wait(10)
    builds.poll()
    assert shown == {"A": "pom", "B": "relief"} and builds.current is None and problems == []


def test_a_failed_background_build_is_reported_and_not_retried_until_asked_again():
    renderer = FakeRenderer(built={"normal"}, bad={"pom"})
    builds, shown, problems = builds_for(renderer, background=True)
    builds.request("A", "pom")
    assert builds.current.wait(10)
    builds.poll()
    assert problems == ["pom: damaged texture"] and shown["A"] == "normal"
    assert builds.wanted["A"] == "normal" and builds.current is None
    builds.poll()
    assert renderer.prepared == ["pom"]  # not built again by itself
    builds.request("A", "pom")
    assert builds.current is not None and builds.current.wait(10)
    assert renderer.prepared == ["pom", "pom"]


def test_a_build_no_longer_wanted_is_not_shown():
    gate = threading.Event()
    renderer = FakeRenderer(built={"normal", "parallax"}, gate=gate)
    builds, shown, _ = builds_for(renderer, background=True)
    builds.request("A", "pom")
    builds.request("A", "parallax")  # ready: shown at once, pom is no longer wanted there
    gate.set()
    assert builds.current.wait(10)
    builds.poll()
    assert shown["A"] == "parallax" and builds.current is None


class SteppedRenderer(FakeRenderer):
    """Builds a technique's maps one by one, reporting each before building it (as Renderer.prepare does); the
    first sets ``building`` and waits for ``gate``."""

    def __init__(self, *args, **kwargs):
        super().__init__(*args, **kwargs)
        self.building = threading.Event()

    def prepare(self, name, progress=None):
        for done, step in enumerate(("normal", "depth", "distance")):
            progress(f"m.{step}", done, 3)
            if done == 0:
                self.building.set()
                self.gate.wait(10)
            self.prepared.append(f"{name}:{step}")
        self.built.add(name)


def test_closing_the_window_stops_a_build_after_the_map_under_way_and_waits_for_it(capsys):
    gate = threading.Event()
    renderer = SteppedRenderer(built={"normal"}, gate=gate)
    builds, shown, problems = builds_for(renderer, background=True)
    builds.request("A", "distance")
    build = builds.current
    assert renderer.building.wait(10)
    builds.cancel()  # the window starts closing while the first map builds
    assert not build.finished
    threading.Timer(1.5, gate.set).start()  # the map under way takes a while: stop() says why it waits
    builds.stop()
    assert build.finished and builds.current is None
    assert renderer.prepared == ["distance:normal"]  # finished; depth and distance were never started
    assert shown["A"] == "normal" and problems == [] and build.error is None
    assert capsys.readouterr().err == ("wgpuviewer: the window has closed; the distance build stops once m.normal "
                                       "is built\n")


def test_stopping_without_a_build_under_way_does_nothing():
    builds, shown, problems = builds_for(FakeRenderer(built={"normal"}), background=True)
    builds.cancel()
    builds.stop()
    assert builds.current is None and shown["A"] == "normal" and problems == []


def test_the_build_line_counts_maps_and_estimates_the_time_left():
    from wgpuviewer.viewer.builds import progress_line

    assert progress_line("distance", "", 0, 0, 0.2) == "building distance: finishing, 0 s"  # nothing reported yet
    assert progress_line("distance", "m.normal", 0, 4, 3.0) == "building distance: m.normal (map 1/4), 3 s"
    assert progress_line("distance", "m.distance", 3, 4, 12.0) == (
        "building distance: m.distance (map 4/4), 12 s, about 4 s left")  # 4 s a map so far, one to go
    assert progress_line("distance", "done", 4, 4, 16.0) == "building distance: finishing, 16 s"


def test_a_build_under_way_reports_its_step_on_the_line():
    gate = threading.Event()
    renderer = SteppedRenderer(built={"normal"}, gate=gate)
    builds, _, _ = builds_for(renderer, background=True)
    builds.request("A", "distance")
    assert renderer.building.wait(10)
    assert builds.current.line().startswith("building distance: m.normal (map 1/3), ")
    gate.set()
    assert builds.current.wait(10)
