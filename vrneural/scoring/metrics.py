"""Image-quality metrics (of `eval` and the benchmarks), against a reference frame.

- :func:`flip_hdr`: HDR-FLIP (NVIDIA ``flip-evaluator``) on linear radiance ``[H, W, 3]``, at a
  given pixels-per-degree; the mean of the per-pixel error map, in ``[0, 1]``.
- :func:`psnr` and :func:`ssim` on display images: :func:`display` maps linear radiance with the
  runtime's tone map (``x / (1 + x)`` then sRGB, as :func:`vrneural.runtime.output.tonemap`,
  unquantised) to ``[0, 1]`` floats, so both see what the headset shows (peak value 1).

SSIM (Wang, Bovik, Sheikh, Simoncelli 2004, Eq. 13): per channel, local means, variances and
covariance with an isotropic Gaussian window (sigma 1.5 px, truncated at 3.5 sigma: 11 x 11),
``K1 = 0.01``, ``K2 = 0.03``, dynamic range ``L = 1``; the SSIM map is averaged over pixels whose
window lies inside the image (a 5-pixel border is dropped) and over the 3 channels.
"""

from __future__ import annotations

import numpy as np

SSIM_SIGMA = 1.5
SSIM_TRUNCATE = 3.5
SSIM_K1, SSIM_K2 = 0.01, 0.03


def display(hdr: np.ndarray) -> np.ndarray:
    """Linear radiance ``[H, W, >=3]`` -> display image ``[H, W, 3]`` float64 in [0, 1]: the
    runtime's tone map (``x / (1 + x)``, then the sRGB curve) without 8-bit quantisation."""
    x = np.maximum(np.nan_to_num(np.asarray(hdr, np.float64)[..., :3]), 0)
    x = x / (1 + x)
    return np.where(x <= 0.0031308, 12.92 * x, 1.055 * np.power(x, 1 / 2.4) - 0.055)


def psnr(a: np.ndarray, b: np.ndarray, peak: float = 1.0) -> float:
    """PSNR in dB of ``b`` against ``a`` (same shape); 100 dB when they are identical."""
    mse = float(np.mean((np.asarray(a, np.float64) - np.asarray(b, np.float64)) ** 2))
    return 100.0 if mse <= 1e-10 * peak**2 else float(10 * np.log10(peak**2 / mse))


def ssim(a: np.ndarray, b: np.ndarray, data_range: float = 1.0) -> float:
    """Mean SSIM of ``b`` against ``a``: ``[H, W]`` or ``[H, W, C]`` (channels averaged)."""
    from scipy.ndimage import gaussian_filter

    a = np.asarray(a, np.float64)
    b = np.asarray(b, np.float64)
    if a.shape != b.shape:
        raise ValueError(f"ssim: shapes differ {a.shape} vs {b.shape}")
    if a.ndim == 2:
        a, b = a[..., None], b[..., None]
    c1 = (SSIM_K1 * data_range) ** 2
    c2 = (SSIM_K2 * data_range) ** 2
    r = int(SSIM_TRUNCATE * SSIM_SIGMA + 0.5)
    out = []
    for ch in range(a.shape[2]):
        x, y = a[..., ch], b[..., ch]

        def blur(z):
            return gaussian_filter(z, SSIM_SIGMA, truncate=SSIM_TRUNCATE, mode="reflect")

        mx, my = blur(x), blur(y)
        vx = blur(x * x) - mx * mx
        vy = blur(y * y) - my * my
        cxy = blur(x * y) - mx * my
        s = ((2 * mx * my + c1) * (2 * cxy + c2)) / ((mx * mx + my * my + c1) * (vx + vy + c2))
        if s.shape[0] > 2 * r and s.shape[1] > 2 * r:
            s = s[r:-r, r:-r]
        out.append(float(s.mean()))
    return float(np.mean(out))


def flip_hdr(ref: np.ndarray, test: np.ndarray, ppd: float) -> float:
    """Mean HDR-FLIP of ``test`` against ``ref`` (linear radiance ``[H, W, >=3]``, >= 0)."""
    return flip_hdr_eyes(np.asarray(ref)[None], np.asarray(test)[None], ppd)


#: blank columns between the eyes of :func:`flip_hdr_eyes` (wider than FLIP's filters at the
#: headset's density, so one eye's error never leaks into the other's pixels)
EYE_GAP = 16


def flip_hdr_eyes(ref: np.ndarray, test: np.ndarray, ppd: float) -> float:
    """Mean HDR-FLIP of ``test`` against ``ref``, both ``[eyes, H, W, >=3]``, over the eyes'
    pixels: one evaluation of the eyes side by side (each call has a large fixed cost), the
    blank gap between them left out of the mean. HDR-FLIP's exposure range comes from the
    reference frame as a whole (both eyes), as it would for the headset's frame."""
    import flip_evaluator

    def side_by_side(x):
        x = np.maximum(np.nan_to_num(np.asarray(x, np.float32)[..., :3]), 0)
        gap = np.zeros((x.shape[1], EYE_GAP, 3), np.float32)
        parts = [p for e in x for p in (e, gap)][:-1]
        return np.ascontiguousarray(np.concatenate(parts, 1))

    a, b = side_by_side(ref), side_by_side(test)
    err, _, _ = flip_evaluator.evaluate(
        a, b, "HDR", inputsRGB=True, applyMagma=False, parameters={"ppd": float(ppd)}
    )
    w = ref.shape[2]
    keep = np.zeros(a.shape[1], bool)
    for e in range(ref.shape[0]):
        keep[e * (w + EYE_GAP) : e * (w + EYE_GAP) + w] = True
    return float(np.asarray(err)[:, keep].mean())


def pixels_per_degree(eye_height: int, fov_y: float) -> float:
    """Pixels per degree of an eye image ``eye_height`` pixels tall spanning ``fov_y`` degrees."""
    return eye_height / fov_y
