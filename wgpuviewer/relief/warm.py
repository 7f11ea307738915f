"""Warming the map cache: every map a technique needs on a scene, built now through the renderer's own requests
(``Renderer.prepare``), so that a later render or viewer session on this adapter finds each one under the key it
looks up. The key holds the height data and every option the renderer asks for (the material's height scale, the
settings chosen for the adapter), which is why warming goes through the renderer and not through ``maptools batch``.
``wgpuviewer warm`` runs it.
"""

from __future__ import annotations

from collections import Counter
from collections.abc import Callable
from dataclasses import dataclass

from maptools.cache import recording
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import Gpu
from wgpuviewer.scene import Scene

from .renderer import Renderer


@dataclass(frozen=True)
class Warmed:
    """What warming one technique did: how many of its cached maps were built now, were in the cache already, or
    came from files the scene names; ``error``: why its maps cannot be built (nothing else then)."""

    technique: str
    built: int = 0
    cached: int = 0
    named: int = 0
    error: str = ""

    @property
    def summary(self) -> str:
        if self.error:
            return f"{self.technique}: FAILED: {self.error}"
        if not self.built + self.cached + self.named:
            return f"{self.technique}: needs no generated map"
        parts = [f"{self.built} built", f"{self.cached} already cached"]
        if self.named:
            parts.append(f"{self.named} from files the scene names")
        return f"{self.technique}: {', '.join(parts)}"


def warm(scene: Scene, gpu: Gpu, technique: str, progress: Callable[[str, int, int], None] | None = None) -> Warmed:
    """Build every map ``technique`` needs on ``scene`` into the cache (a renderer of its own: the count covers all
    of the technique's maps, and its textures are freed after it); a map that cannot be built is reported in the
    result, not raised."""
    with recording() as served:
        try:
            Renderer(scene, gpu).prepare(technique, progress)
        except UserError as error:
            return Warmed(technique, error=str(error))
    sources = Counter(s.source for s in served)
    return Warmed(technique, built=sources["built"], cached=sources["cache"], named=sources["file"])
