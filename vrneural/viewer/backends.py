"""The canvases the viewer draws into, each checked with a one-line error and its fix:

- ``window``: rendercanvas's glfw backend, presenting to the window's own swap chain (the
  surface texture is rendered into directly: no read-back per frame);
- ``jupyter``: rendercanvas's Jupyter backend (a ``jupyter_rfb`` widget; its frames are read
  back and sent to the browser, which is how a notebook shows anything).
"""

from __future__ import annotations

import os
import re
import sys
import warnings

from vrneural.errors import VrnError

INSTALL = "pip install 'vrneural[view]'"
XVFB = "xvfb-run -a vrneural view ... (Debian: apt-get install xvfb)"


def _first_line(e: BaseException) -> str:
    return (str(e).strip().splitlines() or [type(e).__name__])[0]


def check_display(env=None) -> None:
    """A :class:`VrnError` when there is no display server to open a window on (Linux and
    the BSDs: neither ``DISPLAY`` nor ``WAYLAND_DISPLAY``)."""
    env = os.environ if env is None else env
    if sys.platform.startswith(("win", "darwin")):
        return
    if not (env.get("DISPLAY") or env.get("WAYLAND_DISPLAY")):
        raise VrnError(
            "no display to open a window on (neither DISPLAY nor WAYLAND_DISPLAY is set); run "
            f"it in a desktop session, or under a virtual X server: {XVFB}"
        )


def import_glfw():
    """The ``glfw`` module, initialised, or a one-line error: the package missing, its shared
    library not found, or the display not reachable."""
    try:
        import glfw
    except ImportError as e:
        if "shared library" in str(e).lower():
            raise VrnError(
                f"glfw's shared library not found (glfw: {_first_line(e)}); the glfw wheel "
                "bundles one: pip install --force-reinstall glfw, or install the system's: "
                "apt-get install libglfw3 (and unset PYGLFW_LIBRARY if it points elsewhere)"
            ) from None
        raise VrnError(f"the viewer needs glfw and rendercanvas: {INSTALL}") from None
    with warnings.catch_warnings(record=True) as caught:
        warnings.simplefilter("always")
        ok = glfw.init()
    if not ok:
        # glfw's warnings read "(65550) b'X11: Failed to open display :5'": keep the words
        msgs = [
            re.sub(r"^\(\d+\) b?['\"](.*)['\"]$", r"\1", _first_line(w.message)) for w in caught
        ]
        why = "; ".join(msgs) or "glfw.init() failed"
        where = os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY") or "?"
        wayland_only = not os.environ.get("DISPLAY") and os.environ.get("WAYLAND_DISPLAY")
        hint = (
            "; on Wayland without XWayland: PYGLFW_LIBRARY_VARIANT=wayland (and apt-get "
            "install libglfw3-wayland)"
            if wayland_only and os.environ.get("PYGLFW_LIBRARY_VARIANT", "") != "wayland"
            else ""
        )
        raise VrnError(
            f"cannot open the display {where!r} ({why}){hint}; is its server running? "
            f"Without one: {XVFB}"
        )
    return glfw


def window_canvas(size, title: str, vsync: bool):
    """A glfw window (rendercanvas) of ``size = (width, height)`` logical pixels, and its loop."""
    check_display()
    import_glfw()
    try:
        from rendercanvas.glfw import RenderCanvas, loop
    except ImportError:
        raise VrnError(f"the viewer needs rendercanvas and glfw: {INSTALL}") from None
    canvas = RenderCanvas(
        size=size, title=title, update_mode="continuous", max_fps=1000, vsync=vsync
    )
    return canvas, loop


def jupyter_canvas(size, title: str):
    """A Jupyter widget canvas (rendercanvas + jupyter_rfb) and its loop."""
    try:
        from rendercanvas.jupyter import RenderCanvas, loop
    except ImportError:
        raise VrnError(
            f"the Jupyter viewer needs rendercanvas and jupyter_rfb: {INSTALL}"
        ) from None
    canvas = RenderCanvas(size=size, title=title, update_mode="continuous", max_fps=1000)
    return canvas, loop


def target_format(context, adapter) -> tuple[str, str]:
    """``(texture format, view format)`` to configure ``context`` with: an 8-bit format
    without sRGB encoding where the surface offers one (the viewer encodes exactly as
    ``output.tonemap`` does), else the sRGB one viewed as plain unorm when allowed, else the
    sRGB one (then the shader decodes before the hardware encodes again: within 1/255)."""
    caps = _capabilities(context, adapter)
    formats = list(caps.get("formats", [])) or [context.get_preferred_format(adapter)]
    views = list(caps.get("view_formats", []))
    plain = [f for f in formats if f in ("bgra8unorm", "rgba8unorm")]
    if plain:
        return plain[0], plain[0]
    for f in formats:
        base = f.removesuffix("-srgb")
        if f.endswith("-srgb") and base in views:
            return f, base
    if not formats:
        raise VrnError("the canvas offers no texture format to present with")
    return formats[0], formats[0]


def _capabilities(context, adapter) -> dict:
    """What ``context`` can be configured with ({} where this rendercanvas / wgpu release does
    not say: then its preferred format is used)."""
    inner = getattr(context, "_wgpu_context", None)
    try:
        if inner is not None:  # presenting to a window: the surface's own capabilities
            return dict(inner._get_capabilities(adapter))
        return dict(getattr(context, "_capabilities", {}))  # bitmap: what it can download
    except Exception:  # private API moved: fall back to the preferred format
        return {}
