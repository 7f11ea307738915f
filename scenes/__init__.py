"""Package data: shipped as wgpuviewer.scenes (see pyproject.toml)."""
