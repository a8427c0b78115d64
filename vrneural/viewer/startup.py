"""Start-up of the viewer: its configs (`run`'s options with the viewer's defaults), the
scene (as `run` loads it, with the same one-line errors) and the first knob values."""

from __future__ import annotations

import dataclasses
from pathlib import Path

from vrneural.config import resolved
from vrneural.errors import VrnError
from vrneural.runtime.config import RunConfig, resolve
from vrneural.runtime.run import load_run_scene
from vrneural.runtime.scene import Scene
from vrneural.viewer.config import RUN_ONLY, ViewConfig
from vrneural.viewer.state import Live

#: the viewer's defaults where they differ from `run`'s: a desktop-sized single eye
VIEW_DEFAULTS = {"profile": "preview", "eyes": 1}


def configs(config=None, view=None, options: dict | None = None) -> tuple[RunConfig, ViewConfig]:
    """``(RunConfig, ViewConfig)`` from ``config`` / ``view`` (None: defaults) and keyword
    ``options`` naming fields of either; `run`'s options the viewer has no use for (``out``,
    ``video``...) are refused. The viewer's defaults (:data:`VIEW_DEFAULTS`) apply to the
    fields nobody set (left None, in code as on the command line); the RunConfig returned
    is resolved (no field left None but those whose None means "the profile's")."""
    options = dict(options or {})
    run_names = {f.name for f in dataclasses.fields(RunConfig)} - set(RUN_ONLY)
    view_names = {f.name for f in dataclasses.fields(ViewConfig)}
    for k in options:
        if k in RUN_ONLY and k not in view_names:
            raise VrnError(f"View: {k} is an option of `vrneural run`, not of the viewer")
        if k not in run_names | view_names:
            known = ", ".join(sorted(run_names | view_names))
            raise VrnError(f"View: unknown option {k!r} (known: {known})")
    if config is not None and not isinstance(config, RunConfig):
        raise VrnError(f"View: config is a {type(config).__name__}, expected a RunConfig")
    if view is not None and not isinstance(view, ViewConfig):
        raise VrnError(f"View: view is a {type(view).__name__}, expected a ViewConfig")
    cfg = config if config is not None else RunConfig()
    cfg = dataclasses.replace(cfg, **{k: v for k, v in options.items() if k in run_names})
    defaults = {k: v for k, v in VIEW_DEFAULTS.items() if getattr(cfg, k) is None}
    cfg = resolved(dataclasses.replace(cfg, **defaults))
    vc = view if view is not None else ViewConfig()
    view_opts = {k: v for k, v in options.items() if k in view_names}
    if view_opts:
        vc = dataclasses.replace(vc, **view_opts)
    return cfg, vc


def load(scene, cfg: RunConfig):
    """The scene: a :class:`~vrneural.runtime.scene.Scene`, a scene file, or None for the
    built-in one (``--pack`` applied), with `run`'s checks and messages."""
    if scene is not None and not isinstance(scene, (Scene, str, Path)):
        raise VrnError(
            f"View: scene is a {type(scene).__name__}; pass a Scene, a scene file or None"
        )
    return load_run_scene(cfg, scene)


def start_live(renderers, vc: ViewConfig):
    """The first :class:`~.state.Live` knobs: the resolved settings of the configs (checked by
    ``resolve``, so a bad flag is `run`'s one-line error)."""
    cfg = renderers.cfg = dataclasses.replace(renderers.cfg, scene=None, pack=None)
    if cfg.reference and not Path(cfg.reference).is_file():
        raise VrnError(f"--reference = {cfg.reference!r}: file not found")
    s = resolve(
        dataclasses.replace(cfg, reference=cfg.reference if cfg.mode == "reference" else None),
        renderers.scene,
        renderers.adapter,
    )
    if s.mode == "reference":  # the precision the other modes run at
        ref_free = dataclasses.replace(cfg, mode="texture", reference=None, precision="auto")
        precision = resolve(ref_free, renderers.scene, renderers.adapter).precision
    else:
        precision = s.precision
    return Live(
        mode=s.mode,
        reuse=s.reuse,
        schedule=s.schedule,
        precision=precision,
        texture_res=s.texture_res,
        texture_res_given=s.texture_res_given,
        radiance=s.radiance,
        adaptive=s.reuse_budget is not None,
        split=vc.split,
        hud=vc.hud,
    )
