"""`vrneural view`: the runtime live in a window (rendercanvas's glfw backend): keys for every
knob `run` has, an orbit / fly camera, a HUD, a split view against the per-pixel reference."""

from __future__ import annotations

import dataclasses
import sys

from vrneural.config import add_config_args, config_from_args
from vrneural.interrupt import interrupt_saying
from vrneural.runtime.config import RunConfig
from vrneural.viewer.backends import check_display, import_glfw
from vrneural.viewer.config import RUN_ONLY, ViewConfig


def register(sub) -> None:
    p = sub.add_parser(
        "view",
        help="watch the runtime live in a window: keys for every knob, a HUD, a split view",
        description="Render SCENE (TOML; the built-in scene when omitted) live in a window, "
        "with `run`'s renderer and options (defaults here: --profile preview, --eyes 1). "
        "F1 in the window lists the keys; the mouse orbits (left), pans (middle), moves the "
        "selected light (right) and zooms (wheel). Needs a display (or xvfb-run) and the "
        "view extra: pip install 'vrneural[view]'.",
    )
    p.add_argument("scene", nargs="?", default=None, help="scene file (TOML)")
    helps = {  # the viewer's own defaults for two of run's options
        "eyes": "number of eyes (1 or 2) (default: 1)",
        "profile": "device profile: preview (default), quest3, quest2, tiny",
    }
    add_config_args(p, RunConfig, skip=RUN_ONLY, helps=helps)
    add_config_args(p, ViewConfig)
    p.set_defaults(func=main)


def main(args) -> int:
    from vrneural.viewer.view import View  # the stage, when it runs

    check_display()  # before the scene and its shaders take their seconds
    import_glfw()
    cfg = config_from_args(RunConfig, args)
    cfg = dataclasses.replace(cfg, frames=RunConfig().frames)  # --frames is the viewer's own
    vc = config_from_args(ViewConfig, args)
    view = View(args.scene, cfg, vc)
    try:
        sm = view.run()
    except KeyboardInterrupt as e:  # closed by Ctrl-C / SIGTERM: say what was kept, exit 130
        kept = [str(view.recorded)] if view.recorded else []
        kept += [p for p in map(str, view.shots) if p.endswith(".png")]
        if kept:
            raise interrupt_saying(f"(kept {', '.join(kept)})", e) from None
        raise
    print(
        f"view      {sm['frames']} frames, median {sm['fps_median']:.1f} FPS "
        f"(render {sm['render_ms_median']:.1f} ms, present {sm['present_ms_median']:.1f} ms)"
    )
    if sm["recorded"]:
        print(f"  video   {sm['recorded']}")
    for p in sm["screenshots"]:
        if p.endswith(".png"):
            print(f"  shot    {p} (+ .exr, .json)")
    sys.stdout.flush()
    return 0
