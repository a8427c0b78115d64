"""The viewer's targets, measured in one run on the adapter at hand; writes JSON, Markdown and
a PNG plot.

    python -m vrneural.viewer.measure docs/results/viewer.json [--quick] [--force]

1. ``fps``: interactive frames per second of `vrneural view` in a real window (Xvfb when no
   ``DISPLAY``), built-in scene, one eye, N = 4 staggered, HUD on, at the ``preview`` and
   ``quest3`` profiles (window at the eye's size, scale 1), beside ``Renderer.frame`` alone
   offscreen at the same settings and camera in the same run (interleaved repeats): what the
   window costs on top. Target: >= 5 FPS at ``preview`` on lavapipe.
2. ``input_to_photon``: key presses submitted to the window's canvas from another thread at
   random moments while it runs; per press, the time from the event to the end of the
   swap-chain present of the first frame rendered with it, and how many frames were presented
   in between (0: the next frame shows it; nothing queued). The present is timed by wrapping
   the canvas context's present call (measurement only).
"""

from __future__ import annotations

import argparse
import os
import sys
import threading
import time
from pathlib import Path

import numpy as np

from vrneural.bench.report import pyplot, save_png
from vrneural.errors import VrnError
from vrneural.outputs import check_outputs, write_json
from vrneural.viewer.view import View
from vrneural.viewer.xvfb import on_a_display


def offscreen_fps(profile: str, frames: int) -> dict:
    """``Renderer.frame`` alone at the viewer's start-up camera, one eye, as the window does."""
    v = View(profile=profile)  # the same renderer, settings, pose and lights as the window
    r, head = v.r, v.pose()
    r.lights[:] = v.lights
    r.frame(0, 0.0, head)  # compiles, full update
    t0 = time.perf_counter()
    for f in range(1, frames + 1):
        r.frame(f, f / r.s.fps, head)
    r.wait()  # frames in flight: until the last one is done
    dt = time.perf_counter() - t0
    return {"fps": frames / dt, "frame_ms": dt / frames * 1e3}


def window_run(profile: str, frames: int, presses: int = 0, seed: int = 0) -> dict:
    """`vrneural view` in a window for ``frames`` frames (after 3 warm-up ones); with
    ``presses``, a thread submits that many ``]`` / ``[`` key presses at random moments."""
    v = View(profile=profile)
    w, h = v.image_size()
    v.vc.window = f"{w}x{h}"  # scale 1
    v.vc.frames = frames + 3
    swaps: dict[int, float] = {}
    state = {"frame": -1}

    def wrap(view, rec):
        if rec.frame == 0:
            ctx = view.canvas._canvas_context
            present = ctx._rc_present

            def timed(**kw):
                out = present(**kw)
                swaps[state["frame"]] = time.perf_counter()
                return out

            ctx._rc_present = timed
        state["frame"] = rec.frame  # rendercanvas presents this frame right after its draw

    v.after_frame(wrap)
    sent: list[tuple[float, str]] = []
    stop = threading.Event()

    def presser():
        rng = np.random.default_rng(seed)
        while len(v.records) < 4 and not stop.is_set():
            time.sleep(0.05)
        for k in range(presses):
            if stop.wait(rng.uniform(0.15, 0.6)):
                return
            ev = {"event_type": "key_down", "key": "]" if k % 2 == 0 else "[", "modifiers": ()}
            v.canvas.submit_event(ev)  # time_stamp set here (perf_counter)
            sent.append((ev["time_stamp"], ev["key"]))

    th = threading.Thread(target=presser, daemon=True)
    th.start()
    try:
        v.run()
    finally:
        stop.set()
        th.join(timeout=5)
    recs = list(v.records)[3:]
    ends = np.array([swaps.get(r.frame, r.end) for r in recs])
    out = {
        "fps": (len(ends) - 1) / (ends[-1] - ends[0]) if len(ends) > 1 else 0.0,
        "render_ms_median": float(np.median([r.render_ms for r in recs])),
        "present_pass_ms_median": float(np.median([r.present_ms for r in recs])),
        "swap_present_ms_median": float(
            np.median([swaps[r.frame] - r.end for r in recs if r.frame in swaps]) * 1e3
        ),
        "frames": len(recs),
        "window": [w, h],
    }
    if presses:
        out["presses"] = _latencies(v, sent, swaps)
    return out


def _latencies(v, sent, swaps) -> dict:
    """Per key press: ms from the event to the swap of the first frame that shows it, and the
    frames presented between the event and that frame (0 = the next frame)."""
    recs = list(v.records)
    lat, late, wrong = [], [], 0
    for stamp, key in sent:
        shown = next((r for r in recs if any(i[1] == stamp for i in r.inputs)), None)
        if shown is None or shown.frame not in swaps:
            continue
        before = [r for r in recs if r.frame < shown.frame]
        prev_reuse = before[-1].settings["reuse"] if before else None
        want = prev_reuse + (1 if key == "]" else -1) if prev_reuse is not None else None
        if want is not None and shown.settings["reuse"] != want:
            wrong += 1
        lat.append((swaps[shown.frame] - stamp) * 1e3)
        # frames whose present ended after the event, before the one that shows it
        late.append(sum(1 for r in before if swaps.get(r.frame, 0) > stamp))
    lat_a = np.asarray(lat)
    return {
        "n": len(lat),
        "all_ms": [round(x, 2) for x in lat],
        "latency_ms": {
            "median": float(np.median(lat_a)) if len(lat_a) else None,
            "p95": float(np.percentile(lat_a, 95)) if len(lat_a) else None,
            "max": float(lat_a.max()) if len(lat_a) else None,
        },
        "frames_presented_in_between": {str(k): late.count(k) for k in sorted(set(late))},
        "presses_not_in_their_frame": wrong,
        "note": "in between = frames whose present ended after the key event but before the "
        "frame showing it: 1 when the event arrives during a frame's rendering (that frame, "
        "already underway, finishes first), 0 when it arrives between frames; the frame "
        "rendered next always shows it (presses_not_in_their_frame = 0)",
    }


def measure(quick: bool = False) -> dict:
    from vrneural.gpu.device import adapter_summary

    n = 8 if quick else 30
    res: dict = {"adapter": adapter_summary().to_dict(), "cpus": os.cpu_count()}
    res["load_before"] = os.getloadavg()[0]
    for profile, frames, reps in (("preview", n, 2), ("quest3", max(4, n // 3), 1)):
        runs = []
        for _ in range(reps):  # interleaved: the machine's load drifts
            off = offscreen_fps(profile, frames)
            win = window_run(profile, frames)
            runs.append({"offscreen": off, "window": win})
        off_fps = float(np.median([r["offscreen"]["fps"] for r in runs]))
        win_fps = float(np.median([r["window"]["fps"] for r in runs]))
        res[profile] = {
            "offscreen_fps": off_fps,
            "window_fps": win_fps,
            "window_cost_pct": (off_fps / win_fps - 1) * 100 if win_fps else None,
            "runs": runs,
        }
    res["preview"]["target_fps"] = 5.0
    res["preview"]["met"] = res["preview"]["window_fps"] >= 5.0
    res["input_to_photon"] = window_run("preview", 30 if quick else 160, 8 if quick else 30)
    res["load_after"] = os.getloadavg()[0]
    return res


def markdown(res: dict) -> str:
    a = res["adapter"]
    lines = [
        "# `vrneural view`: interactive FPS and input-to-photon",
        "",
        f"Adapter {a['name']} ({a['backend']}), {res['cpus']} CPUs; load average "
        f"{res['load_before']:.1f} before, {res['load_after']:.1f} after (other jobs shared "
        "the machine). Built-in scene, one eye, N = 4 staggered, HUD on, window at scale 1.",
        "",
        "| profile | eye | Renderer.frame offscreen | window (view) | window cost |",
        "|---|---|---|---|---|",
    ]
    for p in ("preview", "quest3"):
        r = res[p]
        w = r["runs"][0]["window"]["window"]
        lines.append(
            f"| {p} | {w[0]}x{w[1]} | {r['offscreen_fps']:.2f} FPS | **{r['window_fps']:.2f} FPS** "
            f"| +{r['window_cost_pct']:.0f}% |"
        )
    lines.append("")
    pv = res["preview"]
    lines.append(
        f"Target: >= 5 FPS at preview: **{'met' if pv['met'] else 'not met'}** "
        f"({pv['window_fps']:.2f} FPS). Where a window frame goes (preview, median): "
        f"Renderer.frame {pv['runs'][0]['window']['render_ms_median']:.0f} ms; HUD text and "
        f"the present pass recorded {pv['runs'][0]['window']['present_pass_ms_median']:.0f} ms; "
        f"the swap-chain present (waits for the present pass on the GPU, then the copy to "
        f"the X server) {pv['runs'][0]['window']['swap_present_ms_median']:.0f} ms."
    )
    ip = res["input_to_photon"]["presses"]
    lat = ip["latency_ms"]
    lines += [
        "",
        f"Input-to-photon ({ip['n']} key presses at random moments, preview): median "
        f"{lat['median']:.0f} ms, p95 {lat['p95']:.0f} ms, max {lat['max']:.0f} ms from the key "
        f"event to the end of the swap of the frame showing it; frames presented in between: "
        f"{ip['frames_presented_in_between']} (count per number); presses whose frame did not "
        f"show them: {ip['presses_not_in_their_frame']}.",
        "",
        ip["note"] + ".",
    ]
    return "\n".join(lines) + "\n"


def plot(res: dict, path) -> None:
    plt = pyplot()

    fig, (a, b) = plt.subplots(1, 2, figsize=(10, 3.6))
    profiles = ["preview", "quest3"]
    x = np.arange(len(profiles))
    a.bar(x - 0.2, [res[p]["offscreen_fps"] for p in profiles], 0.4, label="Renderer.frame")
    a.bar(x + 0.2, [res[p]["window_fps"] for p in profiles], 0.4, label="vrneural view window")
    a.axhline(5, color="k", lw=0.8, ls="--", label="target (preview)")
    a.set_xticks(x, profiles)
    a.set_ylabel("frames per second")
    a.set_title(f"one eye, N = 4 ({res['adapter']['name'].split(' (')[0]})")
    a.legend(fontsize=8)
    run = res["input_to_photon"]
    sent = run["presses"]
    frame_ms = 1e3 / run["fps"] if run["fps"] else 0.0
    b.hist(sent["all_ms"], bins=12, color="C2")
    for k in (1, 2):
        b.axvline(k * frame_ms, color="k", lw=0.8, ls=":")
    b.set_title(f"input-to-photon, {sent['n']} key presses (preview)")
    b.set_xlabel(f"ms from key to its frame's swap (dotted: 1, 2 x {frame_ms:.0f} ms)")
    b.set_ylabel("presses")
    fig.tight_layout()
    save_png(fig, path, dpi=110, bbox=None)


def main(argv=None) -> int:
    p = argparse.ArgumentParser(
        prog="python -m vrneural.viewer.measure",
        description=__doc__,
        formatter_class=argparse.RawDescriptionHelpFormatter,
    )
    p.add_argument("out", help="results JSON (Markdown and PNG beside it)")
    p.add_argument("--quick", action="store_true", help="fewer frames (a smoke run)")
    p.add_argument("--force", action="store_true", help="overwrite existing results")
    a = p.parse_args(argv)
    try:
        if not a.out.endswith(".json"):
            raise VrnError(f"{a.out}: the results file must end in .json")
        out = Path(a.out)
        check_outputs([out, out.with_suffix(".md"), out.with_suffix(".png")], a.force)
        res = on_a_display(lambda: measure(a.quick), 2400, 2400)
        write_json(out, res)
        from vrneural.outputs import atomic_path

        with atomic_path(out.with_suffix(".md")) as tmp:
            tmp.write_text(markdown(res))
        plot(res, out.with_suffix(".png"))
    except VrnError as e:
        print(f"vrneural.viewer.measure: error: {e}", file=sys.stderr)
        return 2
    print(markdown(res))
    return 0


if __name__ == "__main__":
    sys.exit(main())
