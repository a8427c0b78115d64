"""Reuse schedules: burst updates once per N+1 frames; staggered covers every block once."""

import numpy as np
import pytest
from runtime_helpers import quad_atlas

from vrneural.runtime.schedule import frame_slice


@pytest.mark.parametrize("n", [0, 1, 4, 6])
def test_burst_updates_exactly_once_per_period(n):
    updates = [frame_slice(f, n, "burst").update for f in range(7 * (n + 1))]
    for start in range(0, len(updates), n + 1):
        assert sum(updates[start : start + n + 1]) == 1
        assert updates[start]
    assert all(s.period == 1 for s in map(lambda f: frame_slice(f, n, "burst"), range(5)))


@pytest.mark.parametrize("n", [0, 1, 4])
@pytest.mark.parametrize("rows", [1, 7, 600])
def test_staggered_covers_every_row_once_per_period(n, rows):
    for start in (0, 3):
        hits = np.zeros(rows, int)
        for f in range(start, start + n + 1):
            s = frame_slice(f, n, "staggered")
            for r in range(s.phase, rows, s.period) if s.update else ():  # the rows it covers
                hits[r] += 1
        assert (hits == 1).all()


@pytest.mark.gpu
def test_gpu_staggered_writes_each_block_once(rng):
    """Phases 0..N on the GPU write disjoint texel sets whose union is the full update."""
    from vrneural.material import random_material
    from vrneural.runtime import texture_pass

    at = quad_atlas(32)
    mat = random_material(2)
    eye, lp, lc = np.float32([0.2, 0.1, 1.2]), np.float32([[0, 0.3, 1]]), np.float32([[1, 1, 1]])
    full, cfull = texture_pass.shade_texture_space(at, mat, np.eye(4), eye, lp, lc)
    n = 4
    written = np.zeros(full.shape[:2], int)
    acc = np.zeros_like(full)
    shaded = 0
    for phase in range(n + 1):
        part, c = texture_pass.shade_texture_space(
            at, mat, np.eye(4), eye, lp, lc, phase=phase, period=n + 1
        )
        written += part[..., 3] > 0
        acc += part
        shaded += c[0]
    assert (written <= 1).all()
    np.testing.assert_array_equal(written, full[..., 3] > 0)
    assert shaded == cfull[0]
    np.testing.assert_array_equal(acc, full)
