"""Package data: shipped as wgpuviewer.wgsl (see pyproject.toml)."""
