"""Temporal shimmer (after the pixel-filter-aware-mipmaps paper's Fig. 4): a static view of an
object rotating 0.1 degree per frame.

Rotating the object by -0.1 degree per frame under a fixed camera and fixed lights is rendered as
the camera and the lights orbiting the (static) object together by +0.1 degree per frame about
its vertical axis: the same images, using only the renderer's public head path and circling
lights (and assigning the renderer's ``head`` path). One neural sphere (the distilled student),
one eye. Measured: the mean absolute frame-to-frame change of the tone-mapped display image over
the object's pixels, per variant, and its ratio to the reference's (teacher per pixel): 1 means
the variant changes no more than the true motion does;
above 1 is shimmer (or stale-update popping) on top of it. The figure stacks the image's middle
column over time (one column per frame) for each variant.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from vrneural.bench import metrics
from vrneural.bench import report as rp
from vrneural.runtime.camera import HeadPath, look_rotation

DEG_PER_FRAME = 0.1
CENTRE = (0.0, 0.9, 0.0)


@dataclass
class OrbitAround(HeadPath):
    """Camera on a horizontal circle about ``centre`` (radius ``radius`` m, ``height`` m above
    it), looking at it, turning ``360 / period`` degrees per second."""

    centre: tuple = CENTRE
    radius: float = 0.8
    height: float = 0.25
    period: float = 40.0
    phase: float = np.pi / 2

    def pose(self, t: float):
        a = self.phase + 2 * np.pi * t / self.period
        c = np.asarray(self.centre, np.float64)
        p = c + np.array([self.radius * np.cos(a), self.height, self.radius * np.sin(a)])
        return p, look_rotation(c - p)


def shimmer_scene(mat, period: float):
    from vrneural.runtime.lights import PointLight
    from vrneural.runtime.scene import MaterialDesc, ObjectDesc, Scene, model_matrix

    from vrneural.runtime.assets import get_mesh

    pos = get_mesh("sphere").positions
    scale = 0.6 / float((pos.max(0) - pos.min(0)).max())  # 0.6 m across, 0.8 m from the eye
    m = MaterialDesc("neural", mat, "student", 1.0)
    obj = ObjectDesc("sphere", "sphere", model_matrix(CENTRE, (0, 0, 0), scale), m)
    lights = [  # circling the object with the camera: fixed relative to the view
        PointLight(
            (CENTRE[0], 2.0, CENTRE[2]),
            (1.0, 0.95, 0.9),
            2.0,
            "circle",
            1.0,
            period,
            np.pi / 2 + 0.6,
        ),
        PointLight(
            (CENTRE[0], 1.2, CENTRE[2]),
            (0.8, 0.9, 1.0),
            1.0,
            "circle",
            1.2,
            period,
            np.pi / 2 - 1.2,
        ),
    ]
    return Scene("shimmer", [obj], lights, None, None, "orbit")


def run_shimmer(mats: dict, c, eye_res, png) -> dict:
    from vrneural.runtime.profiles import get_profile
    from vrneural.runtime.renderer import Renderer, Settings

    prof = get_profile("quest3")
    period = 360.0 / DEG_PER_FRAME / prof.fps  # seconds per revolution
    variants = {
        "reference (teacher per pixel)": ("reference", 0, "burst"),
        "student per pixel": ("screen", 0, "burst"),
        "texture N=0": ("texture", 0, "burst"),
        f"texture N={c.base_reuse} staggered": ("texture", c.base_reuse, "staggered"),
        f"texture N={c.base_reuse} burst": ("texture", c.base_reuse, "burst"),
    }
    out: dict = {
        "deg_per_frame": DEG_PER_FRAME,
        "frames": c.shimmer_frames,
        "texture_res": c.base_res,
        "eye_res": list(eye_res),
        "variants": {},
    }
    cols, mask = {}, None
    for name, (mode, reuse, sched) in variants.items():
        s = Settings(
            eyes=1,
            reuse=reuse,
            texture_res=c.base_res,
            eye_res=tuple(eye_res),
            frames=c.shimmer_frames,
            fps=prof.fps,
            fov_y=prof.fov_y,
            n_lights=2,
            mode=mode,
            schedule=sched,
            precision="f32",
            reference=mats["teacher"] if mode == "reference" else None,
        )
        r = Renderer(shimmer_scene(mats["student"], period), s)
        r.head = OrbitAround(period=period)
        disp = []
        for f in range(c.shimmer_frames):
            r.frame(f)
            disp.append(metrics.display(r.read_eyes()[0]))
        if mask is None:  # the object's pixels: lit in some reference frame (first variant)
            mask = np.max([d.max(-1) for d in disp], 0) > 0
            out["object_pixels"] = int(mask.sum())
        ch = metrics.frame_change([d[mask] for d in disp[1:]])  # frame 0: first update
        out["variants"][name] = {"per_frame_change": ch, "mean_change": float(np.mean(ch))}
        cols[name] = np.stack([d[:, d.shape[1] // 2] for d in disp[1:]], 1)
    ref = out["variants"]["reference (teacher per pixel)"]["mean_change"]
    for v in out["variants"].values():
        v["ratio_to_reference"] = v["mean_change"] / max(ref, 1e-12)
    figure(out, cols, png)
    return out


def figure(out: dict, cols: dict, png) -> None:
    n = len(cols)
    rows = np.flatnonzero(next(iter(cols.values())).max(axis=(1, 2)) > 0)  # the object's rows
    lo, hi = (int(rows.min()), int(rows.max()) + 1) if len(rows) else (0, None)
    fig, axes = rp.figure(2.2 * n + 4, 3.6, n + 1)
    for ax, (name, img) in zip(axes, cols.items(), strict=False):
        ax.imshow(img[lo:hi], aspect="auto", interpolation="nearest")
        ax.set_title(name, fontsize=7)
        ax.set_xlabel("frame")
        ax.set_yticks([])
    ax = axes[-1]
    for name, v in out["variants"].items():
        ax.plot(v["per_frame_change"], label=f"{name} ({v['ratio_to_reference']:.2f}x)")
    ax.set_xlabel("frame")
    ax.set_ylabel("mean |frame - previous|")
    ax.legend(fontsize=6)
    fig.suptitle(
        f"temporal shimmer: object rotating {out['deg_per_frame']} deg/frame, middle "
        "column over time",
        fontsize=9,
    )
    rp.save_png(fig, png)


def markdown(sh: dict) -> list[str]:
    rows = [[k, v["mean_change"], v["ratio_to_reference"]] for k, v in sh["variants"].items()]
    return [
        "",
        f"## Temporal shimmer ({sh['deg_per_frame']} deg/frame, {sh['frames']} frames, "
        f"texture {sh['texture_res']}^2, one eye at {sh['eye_res'][0]}x{sh['eye_res'][1]})",
        "",
        *rp.table(["variant", "mean frame-to-frame change", "x reference"], rows),
    ]
