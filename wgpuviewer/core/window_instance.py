"""The wgpu-native instance a window presents from, and what an adapter can do with a window's surface.

wgpu-py creates one global wgpu-native instance, on the first adapter request. Created without a display handle,
wgpu-native's OpenGL backend (EGL) starts on Mesa's "surfaceless" platform, and its adapters cannot present to an
X11 window: ``wgpuSurfaceConfigure`` then panics ("Surface does not support the adapter's queue family") and the
process aborts. ``prepare_instance_for_glfw`` creates the instance with glfw's own X11 ``Display*`` (glfw's: a
second ``XOpenDisplay`` connection makes ``wgpuInstanceCreateSurface`` panic), before any other wgpu call; Vulkan
presents from such an instance too, and offscreen work is unchanged. ``surface_capabilities`` asks wgpu-native what
an adapter can do with a surface before anything configures it: every configure error is a panic in wgpu-native
(an incompatible adapter, a usage or alpha mode the surface lacks).

Both reach into wgpu-py privates (``wgpu.backends.wgpu_native``: ``ffi``, ``lib``, ``_helpers.get_wgpu_instance``,
``_api.find_surface_id_from_canvas``), which is why pyproject.toml pins wgpu to one minor release. Every reach is
here and guarded: a wgpu-py that moved one gives "not prepared" or "unknown" (None), and the window refuses a
backend it cannot check (one line, exit 2), never a crash.
"""

from __future__ import annotations

import sys
import warnings
from dataclasses import dataclass

from . import env

#: The extras the instance was created with (cffi memory: kept alive for the instance's lifetime); None before.
_extras = None


def prepare_instance_for_glfw() -> bool:
    """Create wgpu's instance with glfw's X11 display, so OpenGL adapters can present to glfw windows. Must come
    before any adapter request (which creates the instance without it). True when the instance has the display
    (now or from an earlier call); False where it cannot (not X11, no display, the instance exists already, a
    wgpu-py or glfw without the hooks): the surface check then decides."""
    global _extras
    if _extras is not None:
        return True
    if not sys.platform.startswith(("linux", "freebsd", "openbsd", "netbsd")):
        return False  # Windows, macOS: surfaces need no display handle
    env.prepare_driver_environment()  # what Mesa reads when the instance starts
    try:
        from wgpu.backends.wgpu_native import _helpers, ffi, lib
    except ImportError:
        return False
    if getattr(_helpers, "_the_instance", "moved") is not None:
        return False  # created already (a GPU use came first), or wgpu-py keeps it elsewhere
    display = _glfw_x11_display()
    if not display:
        return False
    try:
        extras = ffi.new("WGPUInstanceExtras *")
        extras.chain.sType = lib.WGPUSType_InstanceExtras
        extras.displayHandle.type = lib.WGPUNativeDisplayHandleType_Xlib
        extras.displayHandle.data.xlib.display = ffi.cast("void *", display)
        _helpers.get_wgpu_instance(extras=extras)
    except Exception:  # noqa: BLE001 -- cffi declarations and wgpu-py privates may move between releases
        return False
    _extras = extras
    return True


def display_given() -> bool:
    """Whether wgpu's instance was created with a window system's display (``prepare_instance_for_glfw``)."""
    return _extras is not None


def _glfw_x11_display() -> int | None:
    """glfw's own X11 ``Display*`` as an int, initialising glfw; None off X11 (Wayland, no display)."""
    try:
        import glfw
    except ImportError:
        return None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore")  # pyGLFW warns (or raises) where there is no display
        try:
            if not glfw.init():
                return None
            if hasattr(glfw, "get_platform") and glfw.get_platform() != glfw.PLATFORM_X11:
                return None
            display = glfw.get_x11_display()
        except Exception:  # noqa: BLE001 -- GLFWError, or a glfw without X11
            return None
    value = getattr(display, "value", display)  # a ctypes pointer or an int
    return int(value) if value else None


@dataclass(frozen=True)
class SurfaceCaps:
    """What an adapter can do with a surface (wgpuSurfaceGetCapabilities)."""

    formats: int  # how many texture formats; 0: the adapter cannot present to the surface
    usages: int  # wgpu.TextureUsage bits the surface's textures allow
    opaque: bool  # the opaque alpha mode (what the window configures) is offered

    @property
    def problem(self) -> str | None:
        """Why the adapter cannot present to the surface, or None."""
        import wgpu

        if not self.formats:
            return "its driver offers no surface format for this window"
        if not self.usages & wgpu.TextureUsage.RENDER_ATTACHMENT:
            return "the window's surface cannot be rendered to"
        if not self.opaque:
            return "the window's surface has no opaque alpha mode"
        return None


def surface_capabilities(context, adapter) -> SurfaceCaps | None:
    """What ``adapter`` can do with the surface of ``context`` (a rendercanvas wgpu context, or wgpu-py's canvas
    context); None when it cannot be asked (no native surface, a wgpu-py that moved its privates)."""
    try:
        from wgpu.backends.wgpu_native import ffi, lib
        from wgpu.backends.wgpu_native._api import find_surface_id_from_canvas

        surface = find_surface_id_from_canvas(context)
        if not surface:
            return None
        caps = ffi.new("WGPUSurfaceCapabilities *")
        status = lib.wgpuSurfaceGetCapabilities(surface, adapter._internal, caps)
        try:
            if status != lib.WGPUStatus_Success:
                return SurfaceCaps(0, 0, False)
            opaque = any(caps.alphaModes[i] == lib.WGPUCompositeAlphaMode_Opaque for i in range(caps.alphaModeCount))
            return SurfaceCaps(int(caps.formatCount), int(caps.usages), opaque)
        finally:
            lib.wgpuSurfaceCapabilitiesFreeMembers(caps[0])
    except Exception:  # noqa: BLE001 -- wgpu-py privates may move between releases
        return None
