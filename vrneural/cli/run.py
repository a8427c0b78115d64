"""`vrneural run`: render a scene with texture-space neural shading and reuse (or a screen-space
comparison mode), offscreen; write PNG/EXR frames or a stereo video and summary.json."""

from __future__ import annotations

from pathlib import Path

from vrneural.config import add_config_args, config_from_args
from vrneural.runtime.config import RunConfig


def register(sub) -> None:
    p = sub.add_parser(
        "run",
        help="render a scene (texture-space neural shading with reuse), write frames + summary",
        description="Render SCENE (TOML; a built-in scene when omitted) offscreen on any "
        "adapter: per-eye radiance textures shaded by the generated student, reused for N "
        "frames, a stereo forward pass; writes OUT/summary.json, PNG frames (+ EXR with "
        "--target hdr, the default), a video.",
    )
    p.add_argument("scene", nargs="?", default=None, help="scene file (TOML)")
    add_config_args(p, RunConfig, skip=("scene",))
    p.add_argument(
        "--quiet", "--no-progress", dest="quiet", action="store_true", help="no progress bar"
    )
    p.set_defaults(func=main)


def main(args) -> int:
    from vrneural.runtime.run import human_summary, run  # the stage, when it runs

    cfg = config_from_args(RunConfig, args, scene=args.scene)
    sm = run(cfg, progress=not args.quiet)
    print(human_summary(sm))
    out = sm["out"]
    pngs = sorted(Path(f).name for f in sm["files"] if f.endswith(".png"))
    print(f"wrote     {out}/")
    for mp4 in (Path(f) for f in sm["files"] if f.endswith(".mp4")):
        what = "left eye | right eye" if sm["resolved"]["eyes"] == 2 else "one eye"
        print(f"  video   {out}/{mp4.name} ({what})")
    if pngs:
        exr = any(f.endswith(".exr") for f in sm["files"])
        print(f"  frames  {', '.join(pngs)}" + (" (+ .exr)" if exr else ""))
    print(f"  summary {out}/summary.json")
    return 0
