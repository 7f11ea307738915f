"""docs/curved.md's rule-limits block on known depths."""

import math

from wgpuviewer.lab.studies.curved import docs


def test_rule_limits_invert_the_first_order_rule():
    # at 45° tan θ = 1: error = depth · S/R · 1.5, so S/R = budget / (1.5 depth)
    text = docs.rule_limits([2.0, 1.0], budget=0.3, angles=(45.0,))
    assert text == "For 0.3 texel the rule allows S/R up to 45°: 0.1 (2 texels deep), 0.2 (1 texels deep)."
    assert math.isclose(0.3 / (1.5 * 2.0), 0.1)
