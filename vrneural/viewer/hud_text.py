"""What the HUD says: FPS, frame ms, per-pass GPU ms (timestamps), the work the frame did,
every knob's value, the lights, the camera, the split view, a status line; F1 adds the keys."""

from __future__ import annotations

import time

from vrneural.viewer.hud import thousands

STATUS_S = 8.0  # seconds a status line stays


def hud_lines(view, st, last) -> tuple[list[str], set[int]]:
    """``(lines, alert line indices)``; ``st``: the newest frame statistics that have come back
    (frames in flight: a frame or two behind the one drawn), or None before the first;
    ``last``: the previous :class:`~vrneural.viewer.frame.FrameRecord` (its render / present
    ms), or None."""
    v, live, s = view, view.live, view.r.s
    texture = s.mode == "texture"
    unit = "blocks" if texture else "pixels"
    if st is None:  # the first frames: still in flight, nothing has come back yet
        gpu, work = "(in flight)", f"{unit} shaded -  MLP evals -"
    else:
        gpu = "  ".join(f"{k} {ms:.1f}" for k, ms in st.gpu_ms.items())
        gpu += "".join(f"  {k} n/a" for k in st.untimed)
        gpu = gpu.strip() or "n/a (no timestamps)"
        shaded = st.blocks_shaded if texture else st.pixels_shaded
        work = (
            f"{unit} shaded {thousands(shaded)}  MLP evals {thousands(st.mlp_coarse + st.mlp_fine)}"
        )
        if texture:
            work += f"  objects updated {st.updated_objects}, culled {st.culled_objects}"
        work += f"  (frame {st.frame})"
    timing = (
        f"render {last.render_ms:.1f}, HUD + present {last.present_ms:.1f}" if last else "first"
    )
    interval = 1e3 / v.fps() if v.fps() > 0 else 0.0
    knobs = f"mode {s.mode}  "
    if texture:
        reuse = f"auto {s.reuse_budget:g} deg" if s.reuse_budget is not None else s.reuse
        shared = "shared radiance  " if s.radiance == "shared" else ""
        knobs += f"N {reuse}  {s.schedule}  {s.precision}  texture {s.texture_res}^2  {shared}"
    else:
        knobs += f"{s.precision} per pixel  "
    knobs += f"eye {s.eye_res[0]}x{s.eye_res[1]} x{s.eyes}"
    lights = "  ".join(
        f"{k + 1}:{'on' if on else 'off'}{'*' if k == live.selected else ''}"
        for k, on in enumerate(live.lights_on)
    )
    camera = "head path" if live.follow_head else v.camera.mode
    lines = [
        f"vrneural view  {v.adapter.name} ({v.adapter.backend})",
        f"FPS {v.fps():5.1f}  frame {interval:6.1f} ms  ({timing} ms)",
        f"GPU ms  {gpu}",
        work,
        knobs,
        f"lights {lights or 'none'}  (* dragged by the right button)",
        f"camera {camera}  t {v.t:.2f} s{' paused' if live.paused else ''}  frame {v.f}",
    ]
    if live.split != "off":
        age = v.f - v.split_frame if v.split_frame is not None else 0
        every = f"every {v.split_every} frames"
        if live.split == "reference":
            line = f"split  {s.mode} | reference (per pixel, f32; {every}, {age} frames old)"
        elif v.flip_mean is not None:
            line = f"split  {s.mode} | FLIP vs reference: mean {v.flip_mean:.4f} (frame "
            line += f"{v.flip_frame}; {every})"
        else:
            line = f"split  {s.mode} | FLIP vs reference: computing (the reference meanwhile)"
        lines.append(line)
    alert = set()
    if v.status and time.perf_counter() - v.status[1] < STATUS_S:
        if v.status[2]:
            alert.add(len(lines))
        lines.append(v.status[0])
    lines.append("F1 keys  F2 HUD" if not live.help else "")
    if live.help:
        lines += v.keymap.help_lines()
    return lines, alert
