"""The window, behind one adapter: the toolkit choice (glfw by default, Qt on request), the rendercanvas canvas and
its wgpu surface, events, the title, vsync and fullscreen.

Every toolkit-specific call and every reach into a rendercanvas private lives here, so that a rendercanvas release
that moves one breaks this module alone (and vsync or fullscreen fail as a message, never the viewer); the wgpu-native
ones (the instance a window presents from, the surface check) live in ``core.window_instance``.

A window opens only on an adapter that can present to it (``Window._check_surface``): configuring a surface the
adapter cannot use is a wgpu-native panic, which aborts the process, so that case is one line instead (``refusal``:
the backend, why, and the backends and the offscreen render that work). A surface whose textures cannot be read back
(OpenGL's: no COPY_SRC) gets frames drawn into a texture of the window's own, copied onto it (``Present``).

From the moment a window opens until its loop ends, SIGINT and SIGTERM only note themselves (``Window.note_signals``);
the loop closes the window for them and ``Window.run`` raises ``SignalQuit`` after it (the runner's exit 130/143).
"""

from __future__ import annotations

import signal
import threading

import wgpu

from wgpuviewer.core import window_instance
from wgpuviewer.core.errors import UserError
from wgpuviewer.core.gpu import BACKENDS, fullscreen_pipeline, list_adapters
from wgpuviewer.core.wgsl import compose

#: wgpu's backend_type -> the --backend name.
BACKEND_NAMES = {kind: name for name, kind in BACKENDS.items()}
#: What the window's frames are used for: drawn into, and read back (scripted runs, P).
FRAME_USAGE = wgpu.TextureUsage.RENDER_ATTACHMENT | wgpu.TextureUsage.COPY_SRC
#: The signals a window of its own (not a notebook's) notes instead of raising (``Window.note_signals``).
NOTED_SIGNALS = (signal.SIGINT, signal.SIGTERM)
#: How often the event loop looks for a noted signal (the window may draw no frames: minimised).
POLL_SECONDS = 0.05


class SignalQuit(Exception):
    """The window's loop ended for a signal (``Window.run``): ``signum``."""

    def __init__(self, signum: int):
        super().__init__(f"signal {signum}")
        self.signum = signum


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


def prepare_gpu(gui: str) -> None:
    """Call before the window's GPU starts (before any adapter request): a glfw window on X11 needs wgpu's instance
    to know glfw's display, or OpenGL adapters cannot present to it (``core.window_instance``)."""
    if gui == "glfw":
        window_instance.prepare_instance_for_glfw()


def refusal(adapter, problem: str, context) -> UserError:
    """One line: the backend cannot present to this window, why, and what works instead (the backends whose
    adapters can present to this window, and rendering offscreen)."""
    name = BACKEND_NAMES.get(adapter.info.get("backend_type"), adapter.info.get("backend_type"))
    working = []
    for other in list_adapters():
        other_name = BACKEND_NAMES.get(other.info.get("backend_type"))
        caps = window_instance.surface_capabilities(context, other) if other_name not in (None, name) else None
        if caps is not None and caps.problem is None and other_name not in working:
            working.append(other_name)
    instead = "".join(f"--backend {n}, or " for n in working)
    return UserError(f"the {name} backend cannot present to this window ({adapter.summary}: {problem}); use "
                     f"{instead}render offscreen (wgpuviewer render --backend {name}, or view without a display)")


class Window:
    """A rendercanvas window drawing with ``gpu``'s device; ``canvas`` is the rendercanvas object (for the HUD)."""

    def __init__(self, gui: str, gpu, size: tuple[int, int], *, scripted: bool, vsync: bool):
        RenderCanvas, self._loop = toolkit(gui)
        self.gui = gui
        #: SIGINT or SIGTERM once one came in (``note_signals``); the run loop ends the run for it (``runner``).
        self.quit_signal = None
        # From before the toolkit's window exists: its callbacks run from here on, and an exception a signal raises
        # inside one is lost (glfw's ctypes callbacks), so the window would stay open.
        self._signal_handlers = self.note_signals() if gui != "jupyter" else {}
        try:
            self._open(RenderCanvas, gpu, size, scripted, vsync)
        except BaseException:
            self.restore_signals()
            raise

    def _open(self, RenderCanvas, gpu, size, scripted: bool, vsync: bool) -> None:  # noqa: N803 -- a class
        """The canvas, its surface checked and configured."""
        self._device = gpu.device
        self.canvas = RenderCanvas(
            title="wgpuviewer", size=size, update_mode="continuous", max_fps=1000 if scripted else 240, vsync=vsync,
        )
        self.context = self.canvas.get_wgpu_context()
        #: None: frames are the surface's own textures; else they are drawn into a texture of the window's own and
        #: copied onto the surface (``Present``), where the surface's cannot be read back.
        self._present = None
        self._surface_usage = self._check_surface(gpu)
        self.format = self.context.get_preferred_format(gpu.adapter)
        if self._surface_usage != FRAME_USAGE:
            self._present = Present(self._device, self.format)
        self._windowed = ((100, 100), size)  # where leaving fullscreen puts the window
        self._closing = False
        self._closing_handlers = []
        self.canvas.add_event_handler(self._on_canvas_close, "close")
        self._configure()

    def _check_surface(self, gpu) -> int:
        """The usage to configure the surface with; a UserError (the window closed) when ``gpu``'s adapter cannot
        present to it: configuring it would be a wgpu-native panic, which aborts the process."""
        if getattr(self.context, "_wgpu_context", None) is None:
            return FRAME_USAGE  # rendercanvas presents a bitmap (jupyter): textures of its own, no native surface
        caps = window_instance.surface_capabilities(self.context, gpu.adapter)
        problem = caps.problem if caps is not None else None
        if gpu.adapter.info.get("backend_type") == "OpenGL" and not window_instance.display_given():
            if caps is None:  # unknown: configuring would be a gamble with a panic
                problem = "this wgpu-py offers no way to check or prepare its surface"
            elif problem:
                problem += " (the GPU started before the window's display was known)"
        if problem:
            error = refusal(gpu.adapter, problem, self.context)
            self._release_surface()
            self.canvas.close()
            raise error
        if caps is not None and caps.usages & FRAME_USAGE == FRAME_USAGE:
            return FRAME_USAGE  # scripted runs and P read back the frame just drawn
        return wgpu.TextureUsage.RENDER_ATTACHMENT  # always allowed on a surface the adapter can present to

    def _configure(self):
        self.context.configure(device=self._device, format=self.format, usage=self._surface_usage)

    def on(self, handler, *event_types: str) -> None:
        self.canvas.add_event_handler(handler, *event_types)

    def current_texture(self):
        """The texture to draw this frame into (it can be read back); a zero-size window (minimised) cancels the
        frame (wgpu-py refuses a texture with zero pixels)."""
        w, h = self.canvas.get_physical_size()
        if w < 1 or h < 1:
            raise wgpu.DrawCancelled("zero-sized frame")
        if self._present is not None:
            return self._present.frame((w, h))
        return self.context.get_current_texture()

    def logical_size(self) -> tuple[float, float]:
        return self.canvas.get_logical_size()

    def pixel_ratio(self) -> float:
        return self.canvas.get_pixel_ratio()

    def set_title(self, title: str) -> None:
        self.canvas.set_title(title)

    def request_draw(self, draw) -> None:
        if self._present is None:
            self.canvas.request_draw(draw)
            return

        def draw_and_copy():
            draw()
            self._present.copy(self.context.get_current_texture())

        self.canvas.request_draw(draw_and_copy)

    def run(self) -> None:
        """The event loop, until the window closes. A signal noted meanwhile (``note_signals``) closes the window
        from the loop, as Escape does (never from inside a draw or a toolkit callback, where closing would destroy
        the surface under way: a wgpu-native panic), and is raised after the loop as ``SignalQuit``; the handlers
        from before the window opened are back by then. rendercanvas sets its own SIGINT handler (which closes the
        window wherever the signal lands) when its loop starts: the loop's first callback notes the signals again."""

        def poll():
            if self.quit_signal is not None and not self.closed:
                self.close()
            if not self.closed:
                self._loop.call_later(POLL_SECONDS, poll)

        self._loop.call_soon(self.note_signals)
        self._loop.call_soon(poll)
        try:
            self._loop.run()
        finally:
            self.restore_signals()
        if self.quit_signal is not None:
            raise SignalQuit(self.quit_signal)

    def note_signals(self) -> dict:
        """From now on NOTED_SIGNALS only set ``quit_signal`` (a handler that does nothing else may land anywhere:
        inside a draw, inside a toolkit callback); returns the handlers they had. The main thread only (elsewhere
        nothing changes)."""
        if threading.current_thread() is not threading.main_thread():
            return {}

        def note(signum, _frame):
            self.quit_signal = signum

        return {sig: signal.signal(sig, note) for sig in NOTED_SIGNALS}

    def restore_signals(self) -> None:
        """The handlers NOTED_SIGNALS had before the window opened, back."""
        for sig, handler in self._signal_handlers.items():
            signal.signal(sig, handler)
        self._signal_handlers = {}

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


class Present:
    """Frames drawn into a texture of the window's own (which can be read back), copied onto the surface's texture
    by a fullscreen pass (``wgsl/entry/present.wgsl``): for surfaces without COPY_SRC (OpenGL's)."""

    def __init__(self, device, format: str):
        self.device = device
        self.layout, self.pipeline = fullscreen_pipeline(
            device, "present", compose("entry/present.wgsl").code,
            [{"binding": 0, "visibility": wgpu.ShaderStage.FRAGMENT, "texture": {"sample_type": "unfilterable-float"}}],
            format,
        )
        self.format = format
        self.texture = None
        self.group = None

    def frame(self, size: tuple[int, int]):
        """The texture to draw a frame of ``size`` into."""
        if self.texture is None or self.texture.size[:2] != size:
            self.texture = self.device.create_texture(
                label="window:frame", size=(*size, 1), format=self.format,
                usage=FRAME_USAGE | wgpu.TextureUsage.TEXTURE_BINDING,
            )
            self.group = self.device.create_bind_group(
                layout=self.layout, entries=[{"binding": 0, "resource": self.texture.create_view()}])
        return self.texture

    def copy(self, target) -> None:
        """Copy the frame just drawn onto ``target``, the surface's texture."""
        if self.group is None:
            return
        encoder = self.device.create_command_encoder(label="present")
        rpass = encoder.begin_render_pass(label="present", color_attachments=[
            {"view": target.create_view(), "load_op": "clear", "store_op": "store", "clear_value": (0, 0, 0, 1)}])
        rpass.set_pipeline(self.pipeline)
        rpass.set_bind_group(0, self.group)
        rpass.draw(3)
        rpass.end()
        self.device.queue.submit([encoder.finish()])
