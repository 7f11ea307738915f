"""The window, behind one adapter: the toolkit choice (glfw by default, Qt on request), the rendercanvas canvas and
its wgpu surface, events, the title, vsync and fullscreen.

Every toolkit-specific call and every reach into a rendercanvas/wgpu private lives here, so that a rendercanvas
release that moves one breaks this module alone (and vsync or fullscreen fail as a message, never the viewer).
"""

from __future__ import annotations

from wgpuviewer.core.errors import UserError


def toolkit(gui: str):
    """(RenderCanvas class, its loop) of toolkit ``gui``; a missing toolkit is a UserError naming the install."""
    try:
        if gui == "glfw":
            from rendercanvas.glfw import RenderCanvas, loop
        elif gui == "qt":
            import importlib

            for qt in ("PySide6", "PyQt6", "PySide2", "PyQt5"):  # rendercanvas.qt uses the one imported
                try:
                    importlib.import_module(f"{qt}.QtWidgets")
                    break
                except ImportError:
                    continue
            from rendercanvas.qt import RenderCanvas, loop
        else:
            from rendercanvas.auto import RenderCanvas, loop
    except ImportError as error:
        fix = {"glfw": "pip install 'wgpuviewer[window]'", "qt": "pip install PySide6"}.get(gui, "pip install glfw")
        raise UserError(f"--gui {gui}: the window toolkit is missing ({error}); install it with: {fix}") from None
    return RenderCanvas, loop


class Window:
    """A rendercanvas window drawing with ``gpu``'s device; ``canvas`` is the rendercanvas object (for the HUD)."""

    def __init__(self, gui: str, gpu, size: tuple[int, int], *, scripted: bool, vsync: bool):
        RenderCanvas, self._loop = toolkit(gui)
        self.gui = gui
        self._device = gpu.device
        self.canvas = RenderCanvas(
            title="wgpuviewer", size=size, update_mode="continuous", max_fps=1000 if scripted else 240, vsync=vsync,
        )
        self.context = self.canvas.get_wgpu_context()
        self.format = self.context.get_preferred_format(gpu.adapter)
        self._windowed = ((100, 100), size)  # where leaving fullscreen puts the window
        self._configure()

    def _configure(self):
        # COPY_SRC lets scripted runs and P read back the frame just drawn.
        self.context.configure(device=self._device, format=self.format, usage="RENDER_ATTACHMENT|COPY_SRC")

    def on(self, handler, *event_types: str) -> None:
        self.canvas.add_event_handler(handler, *event_types)

    def current_texture(self):
        return self.context.get_current_texture()

    def logical_size(self) -> tuple[float, float]:
        return self.canvas.get_logical_size()

    def pixel_ratio(self) -> float:
        return self.canvas.get_pixel_ratio()

    def set_title(self, title: str) -> None:
        self.canvas.set_title(title)

    def request_draw(self, draw) -> None:
        self.canvas.request_draw(draw)

    def run(self) -> None:
        """The event loop, until the window closes."""
        self._loop.run()

    def close(self) -> None:
        self.canvas.close()

    @property
    def closed(self) -> bool:
        return self.canvas.get_closed()

    def set_vsync(self, on: bool) -> str | None:
        """Vsync picks the surface present mode (fifo vs immediate/mailbox); it needs a reconfigure. Returns why it
        could not change, or None."""
        try:
            self.canvas._vsync = on  # read by rendercanvas when it creates the surface
            inner = getattr(self.context, "_wgpu_context", None)
            if inner is not None:
                inner._present_info["vsync"] = on
            self._configure()
        except Exception as error:  # noqa: BLE001 -- private hooks of rendercanvas/wgpu may move
            return f"could not change the present mode ({error})"
        return None

    def set_fullscreen(self, on: bool) -> str | None:
        """Fullscreen on the primary monitor, or back to where the window was. Returns why not, or None."""
        try:
            if self.gui == "qt" or hasattr(self.canvas, "showFullScreen"):
                self.canvas.showFullScreen() if on else self.canvas.showNormal()
            else:
                import glfw

                window = self.canvas._window
                if on:
                    self._windowed = (glfw.get_window_pos(window), glfw.get_window_size(window))
                    monitor = glfw.get_primary_monitor()
                    mode = glfw.get_video_mode(monitor)
                    glfw.set_window_monitor(window, monitor, 0, 0, mode.size.width, mode.size.height,
                                            mode.refresh_rate)
                else:
                    (x, y), (w, h) = self._windowed
                    glfw.set_window_monitor(window, None, x, y, w, h, 0)
        except Exception as error:  # noqa: BLE001 -- e.g. no monitor, or another toolkit
            return f"not available here ({error})"
        return None
