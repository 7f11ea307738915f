"""``wgpuviewer contact``: the command (``--out``, ``--suite``, ``--backend``, ``--quiet``; no options of its own)."""

from __future__ import annotations

from wgpuviewer.lab.harness.study import StudyCommand


class Contact(StudyCommand):
    pass


STUDY = Contact(
    "contact", "contact-refinement parallax against relief at equal fetches: the same linear search finished by a "
    "second linear search or by a binary search of its bracket, against the float64 exact hit (results.csv, report.md)",
    "output folder (results.csv, report.md)",
    "smoke: two small maps, two angles, one pair (seconds); full: six builtin maps and a photograph, 30-89 degrees, "
    "linear steps 8 and 16 with 1, 2 and 4 extra fetches")
