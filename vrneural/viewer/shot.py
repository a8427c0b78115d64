"""The exact settings of a screenshot, as JSON: enough to render the same frame again (the
resolved settings, the knobs, frame index and scene time, the head pose, the lights as
shaded), plus the adapter and the configs as given."""

from __future__ import annotations

import dataclasses

import numpy as np

from vrneural.config import config_dict
from vrneural.viewer.controls import effective_lights


def quaternion(rot) -> list[float]:
    """Unit quaternion ``[x, y, z, w]`` of a rotation ``[3, 3]`` (pose logs' convention)."""
    from scipy.spatial.transform import Rotation

    return Rotation.from_matrix(np.asarray(rot, np.float64)).as_quat().tolist()


def shot_settings(view) -> dict:
    """What the screenshot of ``view``'s current frame was rendered from."""
    r = view.r
    resolved = dataclasses.asdict(dataclasses.replace(r.s, reference=None))
    resolved["reference"] = view.cfg.reference
    pos, rot = view.pose()
    last = view.records[-1] if view.records else None
    return {
        "written_by": "vrneural view",
        "scene": view.scene.src,
        "frame": view.f,
        "t": view.t,
        "resolved": resolved,
        "knobs": dataclasses.asdict(view.live),
        "head": {
            "position": np.asarray(pos).tolist(),
            "rotation": np.asarray(rot).tolist(),
            "quaternion_xyzw": quaternion(rot),
            "pose_log_row": [0.0, *np.asarray(pos).tolist(), *quaternion(rot)],
            "source": "head path" if view.live.follow_head else f"{view.camera.mode} camera",
        },
        "lights": [
            {**dataclasses.asdict(lt), "position_now": lt.at(view.t).tolist()}
            for lt in effective_lights(view.lights, view.live.lights_on)
        ],
        "split": {
            "mode": view.live.split,
            "reference_frame": view.split_frame,
            "flip_mean": view.flip_mean,
            "flip_frame": view.flip_frame,
        },
        "fps": view.fps(),
        "last_frame_ms": {"render": last.render_ms, "present": last.present_ms} if last else None,
        "adapter": view.adapter.to_dict(),
        "config": config_dict(view.cfg),
        "view": config_dict(view.vc),
        "note": "frame f drives the reuse schedule, t (s) the lights and the head path; "
        "Renderer.frame(frame, t, (position, rotation)) with these lights renders it again "
        "(the radiance textures also depend on the frames before, unless N = 0)",
    }
