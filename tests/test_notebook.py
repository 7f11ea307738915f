"""examples/notebook.ipynb runs top to bottom on a headless kernel (no browser: its widget cell only creates the
widget), and the viewer widget it shows draws frames through rendercanvas's Jupyter backend."""

from __future__ import annotations

from pathlib import Path

import nbformat
from nbclient import NotebookClient
from rendercanvas.jupyter import JupyterRenderCanvas

import wgpuviewer
from tests.relief.scenes import material_scene
from wgpuviewer.viewer.window import toolkit

NOTEBOOK = Path(__file__).resolve().parents[1] / "examples" / "notebook.ipynb"
WIDGET_VIEW = "application/vnd.jupyter.widget-view+json"


def test_the_notebook_is_kept_without_outputs():
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    nbformat.validate(notebook)
    code = [cell for cell in notebook.cells if cell.cell_type == "code"]
    assert code and all(not cell.outputs and cell.execution_count is None for cell in code)


def test_the_notebook_runs_on_a_headless_kernel(tmp_path, adapter):
    notebook = nbformat.read(NOTEBOOK, as_version=4)
    NotebookClient(notebook, timeout=120, kernel_name="python3",
                   resources={"metadata": {"path": str(tmp_path)}}).execute()  # a failing cell raises
    outputs = [output for cell in notebook.cells if cell.cell_type == "code" for output in cell.outputs]
    pictures = [output for output in outputs if "image/png" in output.get("data", {})]
    assert len(pictures) == 3  # a render, the side-by-side comparison, the close-up
    assert WIDGET_VIEW in notebook.cells[-1].outputs[-1]["data"]  # the viewer widget, the last cell's result
    streams = "".join(output.text for output in outputs if output.output_type == "stream" and output.name == "stderr")
    noise = [line for line in streams.splitlines() if line and not line.startswith("notice: no hardware GPU")]
    assert not noise, streams


def test_the_viewer_widget_draws_a_frame(tmp_path, adapter):
    """The frame a browser would get: the widget sized as the browser's resize event sizes it, then drawn."""
    scene = tmp_path / "plane.toml"
    material = 'albedo = { builtin = "bumps", size = [64, 64] }\nheight = { builtin = "bumps", size = [64, 64] }'
    scene.write_text(material_scene(["basic", "pom"], material))
    # rendercanvas's Jupyter backend (jupyter_rfb), checked first: another toolkit's window without a display
    # aborts the process
    assert toolkit("jupyter")[0] is JupyterRenderCanvas
    widget = wgpuviewer.view(scene, "pom", size=(48, 32), camera={"view_angle": 60})
    try:
        widget.handle_event({"event_type": "resize", "width": 48, "height": 32, "pixel_ratio": 1.0})
        widget.force_draw()
        frame = widget.snapshot().data
        assert frame.shape == (32, 48, 4)
        assert frame[:, :, :3].std() > 5  # the plane's relief, not a cleared frame
    finally:
        widget.close()
