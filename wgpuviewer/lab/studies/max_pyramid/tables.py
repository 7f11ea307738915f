"""The study's results files: ``results.csv`` (per height map, angle and walk: its cost and error, each linear
search's cost at equal error and error at equal cost, and for maxmip the twin's check, its steps per level in a
column per level, the paper's "at most 2 steps inside a parent", climbs and early exit), ``levels.csv`` (the twin's
statistics with a ``level`` column) and ``sweep.csv`` (every probed configuration: the cost-error curves)."""

from __future__ import annotations

from wgpuviewer.lab.harness.table import Column, Table

#: Columns steps_l0 .. steps_l{LEVELS-1}: enough for maps up to 2**(LEVELS-1) texels per side.
LEVELS = 9
COMPETITORS = ("steep", "pom", "relief")


def _competitor_columns(name: str) -> tuple[Column, ...]:
    return (
        Column(f"{name}_simd_p95", float, "SIMD-tile fetches to reach the p95 target (interpolated)"),
        Column(f"{name}_flag_p95", str, "'<=': the cheapest setting already meets it; '>': none does"),
        Column(f"{name}_simd_max", float, "SIMD-tile fetches to reach the max target (interpolated)"),
        Column(f"{name}_flag_max", str),
        Column(f"{name}_p95_at_simd", float, "texels: p95 error at the walk's SIMD-tile fetches"),
        Column(f"{name}_flag_p95_at_simd", str, "'>=' / '<=': outside the sweep, a bound"),
        Column(f"{name}_max_at_simd", float, "texels: max error at the walk's SIMD-tile fetches"),
        Column(f"{name}_flag_max_at_simd", str),
    )


TABLE = Table("max-pyramid results", (
    Column("heightmap", str), Column("relief_class", str), Column("angle", float, "degrees at the frame centre"),
    Column("tracer", str, "maxmip or quadmax"), Column("rays", int),
    Column("fetches_mean", float, "fetches per ray"), Column("fetches_simd", float, "fetches per SIMD tile of 8x4"),
    Column("error_p95", float, "texels against the float64 exact hit"), Column("error_max", float, "texels"),
    Column("capped", float, "of the rays"),
    *(c for name in COMPETITORS for c in _competitor_columns(name)),
    Column("twin_same_fetches", float, "rays whose fetch count the twin and the GPU probe agree on"),
    Column("twin_hit_diff", float, "texels: the largest twin-to-probe hit distance"),
    Column("twin_hits_agree", float, "rays whose twin and probe hits are within 0.001 texel"),
    Column("twin_error_max", float, "texels: the twin's (float64) largest hit error against the exact hit"),
    *(Column(f"steps_l{m}", float, f"steps (fetches) per ray at level {m}") for m in range(LEVELS)),
    Column("within_two", float, "parent visits with at most 2 steps inside the parent, all levels"),
    Column("climbs", float, "climbs back up per ray"),
    Column("early_exit_share", float, "rays whose start texel holds the global max"),
    Column("early_exit_error_max", float, "texels: the largest hit error of an early exit"),
    Column("early_exit_simd", float, "SIMD-tile fetches of the walk with the early exit (start texel read)"),
))

LEVELS_TABLE = Table("max-pyramid levels", (
    Column("heightmap", str), Column("relief_class", str), Column("angle", float), Column("level", int),
    Column("steps_per_ray", float, "steps (fetches) per ray at this level"),
    Column("parent_visits", int, "runs of steps at this level inside one parent node"),
    Column("within_two", float, "of those runs, the share with at most 2 steps"),
    Column("most_in_parent", int, "the longest run"),
    Column("climbs_per_ray", float, "climbs from this level to the next per ray"),
))

SWEEP_TABLE = Table("max-pyramid sweep", (
    Column("heightmap", str), Column("relief_class", str), Column("angle", float), Column("technique", str),
    Column("layers", int, "the layer (linear step) count; empty for the walks"),
    Column("fetches_mean", float), Column("fetches_simd", float), Column("error_p95", float),
    Column("error_max", float), Column("capped", float),
))
