"""Seed 000 made to pay: the distance tracer's fetches per pixel on every distance-map variant (the plain map on the
cell-min and the sub-cell solid, the paper's single-cone refined map, sectors, sectors x polar bands), on the
benchmark's views, mean and SIMD-tile, with build times and memory (``wgpuviewer refined-distance``; docs/maps.md
publishes a full run)."""
