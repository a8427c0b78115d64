"""`vrneural view`: the runtime live, in a window (rendercanvas + glfw) or in Jupyter.

    from vrneural.viewer import View
    View().show()                      # Jupyter: the built-in scene, preview profile, one eye
    View("scene.toml", eyes=2).run()   # a window, until it is closed

The viewer is an event loop around :meth:`Renderer.frame
<vrneural.runtime.renderer.Renderer.frame>` (one code path with `vrneural run`): keys change
its knobs, the mouse moves the camera and the lights, and the eyes are tonemapped on the GPU
into the window's own swap chain (:mod:`vrneural.viewer.present`).
"""

from vrneural import lazy_exports
from vrneural.viewer.config import ViewConfig

__all__ = ["View", "ViewConfig"]
# View loads the renderer: on first use (`vrneural view`'s parser needs ViewConfig alone)
__getattr__ = lazy_exports(__name__, {"View": "view"})
