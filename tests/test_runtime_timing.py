"""Timings that are true: every pass's GPU timestamps against the wall clock on a controlled
workload on the adapter at hand (runtime/timecheck.py, Renderer.pass_clock)."""

import numpy as np
import pytest

from vrneural.runtime.scene import builtin_scene
from vrneural.runtime.timecheck import HIGH, LOW


def _times(r, frames, clock: str) -> dict:
    """Median ms per pass over ``frames`` (each a full update: reuse 0), by ``clock``."""
    r.pass_clock = clock
    sts = [r.frame(f) for f in frames]
    r.wait()
    names = {k for st in sts for k in st.gpu_ms}
    return {k: float(np.median([st.gpu_ms.get(k, 0.0) for st in sts])) for k in names}


@pytest.mark.gpu
def test_the_check_classifies_by_its_own_measurement():
    """The renderer's verdict per pass is its measurement: covered exactly when the timestamps
    lie within the band of the wall clock (less an empty submit), or the pass is too short to
    tell."""
    from vrneural.runtime.renderer import Renderer, Settings
    from vrneural.runtime.timecheck import MIN_MS

    r = Renderer(builtin_scene(2), Settings(eyes=2, texture_res=128, eye_res=(64, 64)))
    assert r.timestamp_check is None and r.untimed == ()
    r.frame(0)
    if not r.timer.enabled:
        pytest.skip("no timestamp-query on this adapter")
    assert set(r.timestamp_check) == {"texture", "forward"}
    for name, m in r.timestamp_check.items():
        work = max(m["wall_ms"] - m["overhead_ms"], 0.0)  # medians (the verdict uses extremes)
        if work >= 2 * MIN_MS and not LOW / 2 <= m["timestamp_ms"] / work <= 2 * HIGH:
            assert not m["covered"]  # far off: never taken as covered
        assert (name in r.untimed) == (not m["covered"])


@pytest.mark.gpu
@pytest.mark.parametrize("mode", ["texture", "screen"])
def test_every_pass_is_timed_truly_or_reported_untimed(mode):
    """Frames of a controlled workload (full texture updates / per-pixel shading of the
    built-in scene) rendered twice: passes timed by timestamps in one submit, and each pass
    submitted alone and timed by the wall clock. A pass the renderer times by timestamps agrees
    with its wall time within [1/3, 3]; a pass it reports untimed (FrameStats.untimed) really
    disagrees when its timestamps are read anyway (the detection is not a blanket refusal)."""
    from vrneural.runtime.renderer import Renderer, Settings

    s = Settings(eyes=1, reuse=0, texture_res=256, eye_res=(224, 224), n_lights=3, mode=mode,
                 frames_in_flight=1)  # fmt: skip
    r = Renderer(builtin_scene(3), s)
    if not r.timer.enabled:
        pytest.skip("no timestamp-query on this adapter")
    r.frame(0)
    frames = range(1, 4)
    shading = "texture" if mode == "texture" else "screen"
    untimed = r.untimed
    # up to three rounds of (wall, timestamps): a pass that other processes' load slowed in
    # one wall-clock round (a 2.4 ms pass read as 7.3 ms, once in CI) agrees in the next; a
    # pass whose timestamps do not cover it (0.1 ms against 100 ms) disagrees in every round
    for _ in range(3):
        wall = _times(r, frames, "wall")
        assert {shading, "forward"} <= set(wall) and min(wall.values()) > 1.0
        stamps = _times(r, frames, "timestamps")
        off = []
        for name in ("forward", shading):
            if name in untimed:
                assert name not in stamps
            elif not LOW <= stamps[name] / wall[name] <= HIGH:
                off.append((name, stamps[name], wall[name]))
        if not off:
            break
    assert not off, off
    r.untimed = ()  # read every timestamp, covered or not
    raw = _times(r, frames, "timestamps")
    for name in set(untimed) & {"forward", shading}:
        ratio = raw[name] / wall[name]
        assert not LOW <= ratio <= HIGH, (name, raw[name], wall[name])
