"""docs/shadows.md's hidden-share block on a synthetic timing table."""

from wgpuviewer.lab.studies.shadows import docs


def test_hidden_line_reads_the_occluded_scene():
    times = [{"scene": "open", "hidden": 0.0}, {"scene": "occluded", "hidden": 0.25},
             {"scene": "occluded", "hidden": 0.25}]
    assert docs.hidden_line(times).startswith("The wall hides 25% of the floor's pixels")
    assert docs.hidden_line([{"scene": "open", "hidden": 0.0}]) == "The run timed no occluded scene."
