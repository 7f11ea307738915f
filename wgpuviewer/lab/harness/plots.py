"""The plot context of every report: matplotlib's Agg backend (no window, no display needed) under the project's
style, and PNG saves that go through the atomic writer (a reader never sees half a picture)."""

from __future__ import annotations

import contextlib
import io
from pathlib import Path

from wgpuviewer.core.io import write_bytes

#: The project's plot style: white pictures (also in dark-themed viewers), light grids where an axis asks for one.
STYLE = {"figure.facecolor": "white", "savefig.facecolor": "white", "grid.alpha": 0.3}

#: What a report says instead of its plots when matplotlib is missing.
MISSING = "Plots skipped: matplotlib is not installed (pip install 'wgpuviewer[bench]')."


@contextlib.contextmanager
def pyplot():
    """Yields ``matplotlib.pyplot`` on the Agg backend with ``STYLE`` applied, or None when matplotlib is not
    installed (the report then says ``MISSING``); every figure still open is closed on the way out."""
    try:
        import matplotlib

        matplotlib.use("Agg")
        import matplotlib.pyplot as plt
    except ImportError:
        yield None
        return
    try:
        with matplotlib.rc_context(STYLE):
            yield plt
    finally:
        plt.close("all")


def save_png(fig, path, dpi: int = 110, tight: bool = True) -> str:
    """``fig`` as a PNG at ``path`` (atomically), with its outside legends when ``tight``, then closed; returns the
    file name."""
    import matplotlib.pyplot as plt

    path = Path(path)
    buffer = io.BytesIO()
    fig.savefig(buffer, format="png", dpi=dpi, bbox_inches="tight" if tight else None)
    plt.close(fig)
    write_bytes(path, buffer.getvalue())
    return path.name
