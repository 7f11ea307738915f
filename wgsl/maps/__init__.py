"""Package data: shipped as wgpuviewer.wgsl.maps (see pyproject.toml)."""
