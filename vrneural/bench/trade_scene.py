"""The conditions of `vrneural bench tradeoff`: scenes, head motion and the scored window.

Every condition shows one neural sphere (``SPHERE_M`` across, at eye height ``DIST_M`` in front
of the head unless the condition moves it) lit by two point lights placed relative to it, over a
plain floor. The scored images are crops of the full quest3 eye image (2064 x 2208, 23 pixels per
degree: the headset's real pixel density) that follow the sphere's centre in each eye, so a CPU
adapter scores the true density without rendering 4.5 M pixels per eye.

Conditions (``family``, ``value``): ``rest`` (0 deg/s), ``turn`` (a saccade-like yaw turn at
``value`` deg/s about the neck, :mod:`vrneural.bench.poses`), ``log`` (a user's pose log),
``smooth`` (a slow sway: 5 cm on a 4 s ellipse, looking at the sphere), ``light`` (the key
light circling the sphere at ``value`` deg/s, head still), ``distance`` (the sphere ``value`` m
away) and ``tiling`` (the material tiled ``value`` times), both under the slow sway.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from vrneural.bench import poses
from vrneural.bench.supersample import SupersampledReference
from vrneural.runtime.adaptive import AdaptiveState
from vrneural.runtime.camera import HeadPath, OrbitPath, PoseLogPath
from vrneural.runtime.lights import PointLight, light_arrays
from vrneural.runtime.scene import MaterialDesc, ObjectDesc, Scene, model_matrix
from vrneural.scoring import metrics

SPHERE_M = 0.08  # sphere diameter, metres (about 105 pixels at 1 m on quest3)
DIST_M = 1.0  # default distance head -> sphere centre
TILING = 4.0  # default material tiling on the sphere


@dataclass
class Condition:
    """One condition: how the scene moves and which frames are scored."""

    name: str
    family: str  # rest | turn | log | smooth | light | distance | tiling
    value: float  # deg/s (rest, turn, log, light), metres (distance), repeats (tiling)
    frames: int  # frames rendered (0 .. frames - 1)
    scored: list  # consecutive frames scored
    distance: float = DIST_M
    tiling: float = TILING
    light_speed: float = 0.0  # deg/s of the key light about the sphere
    size: float = SPHERE_M  # sphere diameter, metres
    log: Path | None = None  # pose log (rest, turn, log)
    meta: dict = field(default_factory=dict)

    def head(self) -> HeadPath:
        if self.log is not None:
            return PoseLogPath(self.log)
        # a slow sway, else (light) a head at rest: sway 0, the same pose every frame
        sway = 0.05 if self.family in ("smooth", "distance", "tiling") else 0.0
        return OrbitPath(tuple(poses.HEAD), tuple(self.centre()), sway=sway, period=4.0)

    def centre(self) -> np.ndarray:
        """The sphere's centre (world)."""
        d = poses.TARGET - poses.HEAD
        return poses.HEAD + d / np.linalg.norm(d) * self.distance


def scene_for(c: Condition, mat, reference=None, n_lights: int = 2):
    """The condition's scene with neural material ``mat`` on the sphere (``reference``: the
    teacher pack reference mode shades instead)."""
    from vrneural.runtime.assets import get_mesh

    p = get_mesh("sphere").positions
    scale = c.size / float((p.max(0) - p.min(0)).max())
    centre = c.centre()
    name = mat.meta.get("name", "student")
    desc = MaterialDesc("neural", mat, name, c.tiling, reference=reference)
    floor = MaterialDesc("plain", albedo=(0.35, 0.35, 0.38), specular=0.02, shininess=16.0)
    pfit = get_mesh("plane").positions
    fscale = 8.0 / float((pfit.max(0) - pfit.min(0)).max())
    objects = [
        ObjectDesc("sphere", "sphere", model_matrix(tuple(centre), (0, 0, 0), scale), desc),
        ObjectDesc("floor", "plane", model_matrix((0, 0, 0), (0, 0, 0), fscale), floor),
    ]
    # key light up-left-front of the sphere (as seen from the head), fill light right; both at
    # a distance that scales with the sphere (the same lighting at every distance)
    r = 10 * c.size
    to_head = poses.HEAD - centre
    fwd = to_head / np.linalg.norm(to_head)
    right = np.cross(np.array([0.0, 1.0, 0.0]), fwd)
    right /= np.linalg.norm(right)
    key = centre + r * (0.6 * fwd - 0.5 * right + 0.6 * np.array([0, 1.0, 0]))
    fill = centre + r * (0.5 * fwd + 0.8 * right + 0.1 * np.array([0, 1.0, 0]))
    power = (r / 1.0) ** 2  # 1 W/m^2 at the sphere from the key light
    lights = [PointLight(tuple(key), (1.0, 0.95, 0.9), 2.0 * power)]
    if c.light_speed:
        # the key light circles the sphere horizontally at light_speed deg/s
        lights = [
            PointLight(
                (centre[0], key[1], centre[2]),
                (1.0, 0.95, 0.9),
                2.0 * power,
                "circle",
                float(np.hypot(*(key - centre)[[0, 2]])),
                360.0 / c.light_speed,
                float(np.arctan2(*(key - centre)[[2, 0]])),
            )
        ]
    lights.append(PointLight(tuple(fill), (0.8, 0.9, 1.0), 0.8 * power))
    return Scene("tradeoff", objects, lights[:n_lights], None, None, "orbit", Path.cwd())


def crop_origins(eyes, centre, crop: int, full) -> list[tuple[int, int]]:
    """Per eye, the top-left pixel of the ``crop x crop`` window of the ``full = (w, h)`` eye
    image centred on the projection of ``centre`` (clamped inside the image)."""
    w, h = full
    out = []
    for e in eyes:
        clip = e.view_proj @ np.append(np.asarray(centre, np.float64), 1.0)
        x = (clip[0] / clip[3] + 1) / 2 * w
        y = (1 - clip[1] / clip[3]) / 2 * h
        out.append(
            (int(np.clip(round(x - crop / 2), 0, w - crop)),
             int(np.clip(round(y - crop / 2), 0, h - crop)))
        )  # fmt: skip
    return out


def track(renderer, c: Condition, crop: int, full) -> None:
    """Make ``renderer`` render frame crops that follow the sphere (call before each frame):
    sets ``renderer.head`` and wraps ``renderer.frame``."""
    renderer.head = c.head()
    centre = c.centre()
    frame = renderer.frame

    def framed(f: int):
        renderer.crop_origins = crop_origins(renderer.eyes_at(f), centre, crop, full)
        return frame(f)

    renderer.frame = framed


def turn_condition(
    speed: float, amplitude: float, fps: float, scored: int, d: Path, distance: float = DIST_M
) -> Condition:
    """A built-in saccade log (written to ``d``), the sphere ``distance`` m away; the scored
    window starts halfway through the turn (the stalest part) and runs into the rest after it
    (rest: the same frames)."""
    rows = poses.turn_poses(speed, amplitude, fps=fps)
    path = poses.write_pose_log(d / f"turn-{speed:g}.csv", rows)
    start, n = poses.turn_frames(speed, amplitude, 0.1, fps)
    first = start + max(n // 2, 1)
    fam = "turn" if speed > 0 else "rest"
    name = f"turn {speed:g} deg/s" if speed > 0 else "rest"
    sc = list(range(first, first + scored))
    meta = {"turn_frames": [start, n]}
    return Condition(name, fam, speed, sc[-1] + 1, sc, distance, log=path, meta=meta)


def log_condition(path: Path, fps: float, scored: int, distance: float = DIST_M) -> Condition:
    """A user's pose log: scored around its fastest moment."""
    log = PoseLogPath(path)
    speed = poses.peak_speed(log)
    q = log.q / np.linalg.norm(log.q, axis=1, keepdims=True)
    rate = np.abs((q[1:] * q[:-1]).sum(1))
    k = int(np.argmin(rate)) if len(rate) else 0  # the fastest interval
    first = max(1, int(log.t[k] * fps))
    sc = list(range(first, first + scored))
    return Condition(
        f"log {Path(path).name}", "log", speed, sc[-1] + 1, sc, distance, log=Path(path)
    )


def render(scene, s, cond, crop, full, keep) -> tuple[dict, list]:
    """Frames ``0 .. cond.frames - 1`` in order; returns (frame -> ``[2, H, W, 3]`` for the
    frames in ``keep``, every frame's FrameStats)."""
    from vrneural.runtime.renderer import Renderer

    r = Renderer(scene, s)
    track(r, cond, crop, full)
    imgs, st = {}, []
    for f in range(cond.frames):
        st.append(r.frame(f))
        if f in keep:
            imgs[f] = np.stack([e[..., :3] for e in r.read_eyes()])
    return imgs, st


def reference(scene, s, cond, crop, full, frames, spp, seed) -> dict:
    ref = SupersampledReference(scene, s, spp, seed)
    track(ref.r, cond, crop, full)
    return {f: ref.frame(f) for f in frames}


def reference_pair(scene, s, cond: Condition, score, full, ppd: float, n_floor: int):
    """The supersampled reference (``score``'s spp, seed 0) on ``cond``'s scored frames and a
    second one (seed 1: other sample positions) on the first ``n_floor`` of them; returns
    ``(ref, ref2, those frames, their mean FLIP between the two)``: the noise floor of a score."""
    ref = reference(scene, s, cond, score.crop, full, cond.scored, score.spp, 0)
    nf = cond.scored[:n_floor]
    ref2 = reference(scene, s, cond, score.crop, full, nf, score.spp, 1)
    floor = float(np.mean([metrics.flip_hdr_eyes(ref[f], ref2[f], ppd) for f in nf]))
    return ref, ref2, nf, floor


def scheduled_candidates(r, cond, budget: float | None) -> float:
    """Candidate blocks per displayed frame (frame 0, the first full update, left out) that
    renderer ``r``'s schedule hands the texture-space pass over ``cond``'s frames, with adaptive
    reuse at ``budget`` degrees (None: the fixed N): the schedule alone, nothing shaded."""
    r.s.reuse_budget = budget
    for n in r.neural:
        n.fresh, n.adapt = False, AdaptiveState()
    total = 0
    for f in range(cond.frames):
        todo, _, _ = r._slices(f, r.eyes_at(f), light_arrays(r.lights, f / r.s.fps)[0])
        if f:
            total += sum(n.gatlas.block_list(per)[1][ph][1] for _, n, ph, per in todo)
    return total * r.s.eyes / max(cond.frames - 1, 1)
