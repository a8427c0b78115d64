"""The analytic baseline of the paper's Table 1: a Lafortune fit per texel.

``BTF(u, wi, wo) ~= wi.z * (rho_d(u) + sum_j rho_s,j(u) * max(wo^T M_j(u) wi, 0)^n_j(u))`` with
``j = 1..4`` lobes, a full 3x3 ``M_j`` (shape, orientation, anisotropy; paper Eq. 6-7) and
independent RGB colours: 3 + 4 * (3 + 9 + 1) = 55 parameters per texel (220 bytes as float32,
the paper's 35.2 MB at 400^2). ``wi.z`` carries the BTF's cos(theta_i) (docs/conventions.md sec. 2).

Fitted by Levenberg-Marquardt on the training directions, batched over texels, with
an analytic Jacobian (checked against autograd in the tests), least squares in linear space.
"""

from __future__ import annotations

import math

import torch

N_LOBES = 4
N_PARAMS = 3 + N_LOBES * 13
LOG_N_RANGE = (math.log(0.5), math.log(2000.0))


def _lobes(p: torch.Tensor, A: torch.Tensor):
    """``c = wo^T M_j wi`` and ``s = clamp(c, 0, 1)^n`` for params ``p: [T, 55]`` and
    ``A = outer(wo, wi): [M, 9]``; returns ``c, s: [T, 4, M]``, ``n: [T, 4]``."""
    q = p[:, 3:].reshape(-1, N_LOBES, 13)
    c = torch.einsum("tjk,mk->tjm", q[..., 3:12], A)
    n = torch.exp(q[..., 12])
    inside = (c > 1e-12) & (c < 1)
    logc = torch.log(torch.where(inside, c, torch.ones_like(c)))
    s = torch.where(inside, torch.exp(n[..., None] * logc), (c >= 1).float())
    return c, s, n, inside, logc


def lafortune_eval(p: torch.Tensor, wi: torch.Tensor, wo: torch.Tensor) -> torch.Tensor:
    """BTF values ``[T, M, 3]`` of per-texel parameters ``p: [T, 55]`` at ``wi, wo: [M, 3]``.

    The lobe base ``wo^T M wi`` is clamped to ``[0, 1]`` before the power (unclamped lobes with
    large ``M`` and ``n`` overflow at directions outside the fit).
    """
    A = (wo[:, :, None] * wi[:, None, :]).reshape(-1, 9)
    _, s, _, _, _ = _lobes(p, A)
    rho_s = p[:, 3:].reshape(-1, N_LOBES, 13)[..., :3]  # [T, 4, 3]
    f = p[:, None, :3] + torch.einsum("tjm,tjk->tmk", s, rho_s)
    return f * wi[None, :, 2:3]


def lafortune_jacobian(p: torch.Tensor, wi: torch.Tensor, wo: torch.Tensor) -> torch.Tensor:
    """Analytic Jacobian ``[T, M * 3, 55]`` of :func:`lafortune_eval` (flattened ``[M, 3]``)."""
    T, M = p.shape[0], wi.shape[0]
    A = (wo[:, :, None] * wi[:, None, :]).reshape(-1, 9)
    _, s, n, inside, logc = _lobes(p, A)
    z = wi[:, 2]  # [M]
    q = p[:, 3:].reshape(T, N_LOBES, 13)
    J = torch.zeros(T, M, 3, N_PARAMS, dtype=p.dtype)
    eye = torch.eye(3, dtype=p.dtype)
    J[..., :3] = z[None, :, None, None] * eye  # d/d rho_d
    ds_dc = torch.where(inside, n[..., None] * torch.exp((n[..., None] - 1) * logc), 0)
    ds_dnu = torch.where(inside, s * logc * n[..., None], 0)
    for j in range(N_LOBES):
        o = 3 + 13 * j
        J[..., o : o + 3] = (z[None, :, None] * s[:, j, :, None])[..., None] * eye
        w = z[None, :, None] * q[:, j, None, :3]  # [T, M, 3]: z * rho_s,k
        J[..., o + 3 : o + 12] = w[..., None] * (ds_dc[:, j, :, None] * A[None])[:, :, None, :]
        J[..., o + 12] = w * ds_dnu[:, j, :, None]
    return J.reshape(T, M * 3, N_PARAMS)


def init_params(y: torch.Tensor, wi: torch.Tensor) -> torch.Tensor:
    """Initial ``[T, 55]`` from targets ``y: [T, M, 3]``: least-squares diffuse colour, four
    lobes (two mirror lobes n = 10 and 60, a retro-reflection lobe, a cosine lobe)."""
    T = y.shape[0]
    cz = wi[:, 2]
    rho_d = (y * cz[None, :, None]).sum(1) / (cz * cz).sum().clamp_min(1e-12)
    mats = [(-1, -1, 1, 10.0), (-1, -1, 1, 60.0), (1, 1, 1, 8.0), (0.3, 0.3, 1, 1.0)]
    p = torch.zeros(T, N_PARAMS)
    p[:, :3] = rho_d * 0.8
    for j, (a, b, c, n) in enumerate(mats):
        o = 3 + 13 * j
        p[:, o : o + 3] = 0.05
        p[:, o + 3 : o + 12] = torch.diag(torch.tensor([a, b, c], dtype=torch.float32)).reshape(9)
        p[:, o + 12] = math.log(n)
    return p


def _project(p: torch.Tensor) -> torch.Tensor:
    """Keep colours non-negative and exponents in ``[0.5, 2000]``."""
    p = p.clone()
    p[:, :3] = p[:, :3].clamp_min(0)
    for j in range(N_LOBES):
        o = 3 + 13 * j
        p[:, o : o + 3] = p[:, o : o + 3].clamp_min(0)
        p[:, o + 12] = p[:, o + 12].clamp(*LOG_N_RANGE)
    return p


def fit_lafortune(
    y: torch.Tensor,
    wi: torch.Tensor,
    wo: torch.Tensor,
    iters: int = 40,
    chunk: int = 64,
) -> torch.Tensor:
    """Fit ``[T, 55]`` parameters to ``y: [T, M, 3]`` observed at ``wi, wo: [M, 3]`` (float64
    normal equations for stability), ``chunk`` texels at a time."""

    def res(p, yt):
        return (lafortune_eval(p, wi, wo) - yt).reshape(p.shape[0], -1)

    out = []
    for s in range(0, y.shape[0], chunk):
        yt = y[s : s + chunk]
        p = init_params(yt, wi)
        lam = torch.full((p.shape[0],), 1e-2, dtype=torch.float64)
        cost = (res(p, yt) ** 2).sum(-1).double()
        for _ in range(iters):
            J = lafortune_jacobian(p, wi, wo).double()  # [t, K, P]
            r = res(p, yt).double()
            JtJ = J.transpose(1, 2) @ J
            g = (J.transpose(1, 2) @ r[..., None])[..., 0]
            diag = torch.diagonal(JtJ, dim1=1, dim2=2) + 1e-9
            A = JtJ + torch.diag_embed(lam[:, None] * diag)
            delta = torch.linalg.solve(A, -g[..., None])[..., 0]
            cand = _project(p + delta.float())
            c_new = (res(cand, yt) ** 2).sum(-1).double()
            ok = torch.isfinite(c_new) & (c_new < cost)
            p = torch.where(ok[:, None], cand, p)
            cost = torch.where(ok, c_new, cost)
            lam = torch.where(ok, lam * 0.3, lam * 4).clamp(1e-9, 1e9)
        out.append(p)
    return torch.cat(out)


def predict_lafortune(params: torch.Tensor, wi: torch.Tensor, wo: torch.Tensor) -> torch.Tensor:
    """BTF values ``[T, 3]`` of all texels at one direction pair ``wi, wo: [3]``."""
    return lafortune_eval(params, wi[None], wo[None])[:, 0]
