"""Package list for setuptools (everything else is in pyproject.toml).

pyproject's `packages.find` names a package by its folder, so it cannot ship the top-level wgsl/ and scenes/ folders as
`wgpuviewer.wgsl` / `wgpuviewer.scenes` (pyproject's package-dir maps them); this adds those two to the packages found.
"""

from setuptools import find_packages, setup

setup(packages=[*find_packages(include=["wgpuviewer*", "maptools*"]), "wgpuviewer.wgsl", "wgpuviewer.scenes"])
