"""docs/perspective.md's computed blocks on tiny synthetic rows with known answers."""

from wgpuviewer.lab.studies.perspective import docs
from wgpuviewer.lab.studies.perspective.run import TABLE


def _row(sweep, precision, err, **cells):
    r = TABLE.blank()
    r.update(sweep=sweep, method="incremental", precision=precision, max_err_px=err, max_err=10 * err,
             span_length=3840, tilt_deg=80.0, offset_texels=0.0, adapter="x")
    r.update(cells)
    return r


def test_drift_lines_pick_the_tilts_before_the_horizon_offsets_and_the_float64_ratio():
    rows = [_row("tilt", "float32", 0.5, tilt_deg=30.0), _row("tilt", "float32", 0.25, tilt_deg=89.9),
            _row("tilt", "float32", 9.0, tilt_deg=95.0),
            _row("magnitude", "float32", 2.0, offset_texels=1000.0),
            _row("magnitude", "float32", 8.0, offset_texels=1e6),
            {**_row("magnitude", "float32", 0.5, offset_texels=1e6), "method": "direct"},
            _row("span_length", "float32", 1.0, span_length=64), _row("span_length", "float64", 2.0 ** -10, span_length=64),
            _row("span_length", "float32", 3.0, span_length=128), _row("span_length", "float64", 3 * 2.0 ** -12,
                                                                        span_length=128)]
    tilt, offset, wide = docs.drift_lines(rows)
    assert "0.5 px at 30°, 0.25 px at 89.9°; in texels at 89.9°: 2.5." in tilt and "95°" not in tilt
    assert "2 px at 1000 texels, 8 px at 1e+06 texels" in offset
    assert "`direct` 0.5 px (5 texels) at 1e+06, where float32's spacing is 0.0625 texels" in offset
    assert "2^11.3 times less" in wide and "over 2 span lengths" in wide  # log2 of (2^10 + 2^12) / 2


def test_tieback_limit_names_the_last_magnitude_under_the_bound_and_the_first_over_it():
    relief = [{"magnitude_uv": m, "p99_err": e, "texels": 64, "technique": t}
              for m, e, t in ((0.0, 0.01, "pom"), (0.0, 0.02, "relief"), (100.0, 0.05, "pom"),
                              (100.0, 0.09, "relief"), (1000.0, 0.2, "pom"), (1000.0, 0.01, "relief"))]
    text = docs.tieback_limit(relief, bound=0.1)
    assert text == ("On this 64-texel map every technique's p99 error stays under 0.1 texel up to M = 100 (at most "
                    "0.09 texels) and passes it at M = 1000 (0.2), i.e. |uv| × texture width must stay under about "
                    "64000.")
