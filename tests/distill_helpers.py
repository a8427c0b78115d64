"""An analytic, spatially varying BTF for the distillation tests (no synthesiser needed).

``BTF(u, wi, wo) = (albedo(u) / pi + ks(u) D_ggx(h; alpha(u)) / (4 wi.z wo.z)) * wi.z`` with a
smooth tileable albedo / specular / roughness pattern: a Lambert + GGX patch (docs/conventions.md
section 2: cos(theta_i) inside the BTF).
"""

from __future__ import annotations

import numpy as np
import pytest

from vrneural.btf.dirs import direction_set
from vrneural.btf.format import write_btf


def analytic_btf(path, res: int = 16, n_dirs: int = 6, seed: int = 0, name: str = "analytic"):
    """Write a ``[n_dirs, n_dirs, res, res, 3]`` BTF to ``path`` and return the path."""
    rng = np.random.default_rng(seed)
    d = direction_set(n_dirs)
    y, x = np.meshgrid((np.arange(res) + 0.5) / res, (np.arange(res) + 0.5) / res, indexing="ij")
    ph = rng.uniform(0, 2 * np.pi, 3)
    albedo = 0.5 + 0.35 * np.stack(
        [
            np.sin(2 * np.pi * (x + y) + ph[0]),
            np.cos(2 * np.pi * x + ph[1]),
            np.sin(4 * np.pi * y + ph[2]),
        ],
        -1,
    )  # [H, W, 3]
    ks = 0.3 + 0.25 * np.sin(2 * np.pi * 3 * x)[..., None]
    alpha = 0.25 + 0.15 * np.cos(2 * np.pi * 2 * y)
    wi = d[:, None, :]  # [L, 1, 3]
    wo = d[None, :, :]  # [1, V, 3]
    h = wi + wo
    h = h / np.linalg.norm(h, axis=-1, keepdims=True)
    nh = h[..., 2][..., None, None]  # [L, V, 1, 1]
    a2 = (alpha**2)[None, None]
    D = a2 / (np.pi * (nh**2 * (a2 - 1) + 1) ** 2)
    ci = wi[..., 2][..., None, None] * np.ones_like(nh)
    co = wo[..., 2][..., None, None] * np.ones_like(nh)
    spec = ks[None, None, ..., 0] * D / (4 * ci * co)
    vals = (albedo[None, None] / np.pi + spec[..., None]) * ci[..., None]
    return write_btf(path, vals.astype(np.float32), d, d, {"name": name, "seed": seed})


def run_cli(*argv) -> tuple[int, str]:
    """Run ``vrneural`` in-process; returns ``(exit code, stderr text)``."""
    import contextlib
    import io

    from vrneural.cli import main

    err = io.StringIO()
    with contextlib.redirect_stderr(err):
        code = main([str(a) for a in argv])
    return code, err.getvalue()


def expect_one_line_error(argv, *needles) -> None:
    """``vrneural argv`` exits 2 with one line of stderr holding every one of ``needles``."""
    code, err = run_cli(*argv)
    assert code == 2, err
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    for n in needles:
        assert n in lines[0], lines[0]


FAST = ("--no-progress", "--max-test-slices", "4")


@pytest.fixture(scope="session")
def trained(tmp_path_factory):
    """A 32^2 x (5 x 5 directions) BTF, a 2-epoch teacher and a 2-epoch student (+ packs)."""
    d = tmp_path_factory.mktemp("distill")
    btf = analytic_btf(d / "m.btf", res=32, n_dirs=5)
    t, s = d / "teacher.pt", d / "student.pt"
    code, err = run_cli("teach", btf, "-o", t, "--epochs", 2, *FAST)
    assert code == 0, err
    code, err = run_cli("distill", t, "-o", s, "--epochs", 2, *FAST)
    assert code == 0, err
    return {"dir": d, "btf": btf, "teacher": t, "student": s}
