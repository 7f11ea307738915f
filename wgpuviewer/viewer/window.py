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
        elif gui == "jupyter":  # a notebook widget through jupyter_rfb (wgpuviewer.view)
            from rendercanvas.jupyter import RenderCanvas, loop
        else:
            from rendercanvas.auto import RenderCanvas, loop
    except ImportError as error:
        fix = {"glfw": "pip install 'wgpuviewer[window]'", "qt": "pip install PySide6",
               "jupyter": "pip install 'wgpuviewer[notebook]'"}.get(gui, "pip install glfw")
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
        self._closing = False
        self._closing_handlers = []
        self.canvas.add_event_handler(self._on_canvas_close, "close")
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
        """Close the window from the event loop, once the draw or toolkit callback under way has returned: closing
        destroys the native window, and glfw crashes when that happens inside its own event dispatch (it draws
        frames from a resize callback). ``closed`` is True from this call on."""
        if not self.closed:
            self._start_closing()
            self._loop.call_soon(self.canvas.close)

    @property
    def closed(self) -> bool:
        """Closed, or about to close (``close``, the window manager's close button): no frame may be drawn."""
        return self._closing or self.canvas.get_closed()

    def on_closing(self, handler) -> None:
        """Call ``handler()`` once, when the window starts closing (``close``, the window manager, the loop
        stopping), before ``closed`` turns True."""
        self._closing_handlers.append(handler)

    def _start_closing(self) -> None:
        if not self._closing:
            for handler in self._closing_handlers:
                handler()
            self._closing = True

    def _on_canvas_close(self, event) -> None:
        # rendercanvas sends "close" after unconfiguring the surface and before destroying the native window.
        self._start_closing()
        self._release_surface()

    def _release_surface(self) -> None:
        # The wgpu surface belongs to the native window. Left to the garbage collector (the viewer's objects form
        # cycles) it is released during interpreter exit, in no set order with the device, the instance and the
        # display it depends on, and wgpuSurfaceRelease can crash there. Released here, everything it needs is alive.
        inner = getattr(self.context, "_wgpu_context", None)
        release = getattr(inner, "_release", None)
        if release is not None:
            release()

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
