"""What the viewer writes: screenshots (``P``: PNG + EXR + the exact settings as JSON, never
over an earlier one), the ``--record`` video of what the window showed, and the split view's
FLIP heat map, computed in a worker process (flip-evaluator holds the GIL for seconds at the
preview size, which would freeze the window)."""

from __future__ import annotations

import os
from pathlib import Path

import numpy as np

from vrneural.errors import VrnError
from vrneural.formats.atomic import write_json
from vrneural.runtime.output import write_exr, write_png


def claim_shot(directory: str | Path) -> Path:
    """The next free ``DIR/shot-NNNN`` stem (its ``.json`` created empty, exclusively, so two
    viewers never take one name and nothing earlier is overwritten)."""
    d = Path(directory)
    try:
        d.mkdir(parents=True, exist_ok=True)
    except OSError as e:
        raise VrnError(f"{d}: cannot create the screenshot directory ({e.strerror or e})") from None
    k = 1 + max((int(p.stem[5:]) for p in d.glob("shot-*.json") if p.stem[5:].isdigit()), default=0)
    while True:
        stem = d / f"shot-{k:04d}"
        try:
            fd = os.open(stem.with_suffix(".json"), os.O_CREAT | os.O_EXCL | os.O_WRONLY)
        except FileExistsError:
            k += 1
            continue
        except OSError as e:
            raise VrnError(f"{d}: cannot write a screenshot ({e.strerror or e})") from None
        os.close(fd)
        if stem.with_suffix(".png").exists() or stem.with_suffix(".exr").exists():
            k += 1  # a stray image of that name: leave it, take the next
            continue
        return stem


def save_shot(directory, ldr: np.ndarray, hdr: np.ndarray, settings: dict) -> list[Path]:
    """Write ``shot-NNNN.png`` (``ldr [H, W, 3]`` uint8, what the window shows without the
    HUD), ``.exr`` (``hdr [H, W, 3]`` linear radiance of the same pixels) and ``.json``
    (``settings``); returns the three paths."""
    stem = claim_shot(directory)
    try:
        png = write_png(stem.with_suffix(".png"), ldr)
        exr = write_exr(stem.with_suffix(".exr"), hdr)
        js = write_json(stem.with_suffix(".json"), {**settings, "png": png.name, "exr": exr.name})
    except BaseException:
        for suffix in (".png", ".exr", ".json"):
            stem.with_suffix(suffix).unlink(missing_ok=True)
        raise
    return [png, exr, js]


class Recorder:
    """``--record``: every frame shown, as H.264 (written to a hidden file, renamed at the end;
    frames of another size after a window resize are cropped or padded to the first's)."""

    def __init__(self, path: str | Path, fps: float):
        from vrneural.runtime.output import VideoWriter

        self.path = Path(path)
        self.writer = VideoWriter(self.path, fps)
        self.shape: tuple | None = None
        self.frames = 0

    def add(self, rgb: np.ndarray) -> None:
        if self.shape is None:
            self.shape = rgb.shape
        elif rgb.shape != self.shape:
            out = np.zeros(self.shape, np.uint8)
            h, w = min(rgb.shape[0], self.shape[0]), min(rgb.shape[1], self.shape[1])
            out[:h, :w] = rgb[:h, :w]
            rgb = out
        self.writer.add([rgb])
        self.frames += 1

    def close(self) -> Path | None:
        """Finish the file (None when no frame was recorded: nothing is written)."""
        if not self.frames:
            self.writer.abort()
            return None
        return self.writer.close()


def flip_map(ref: np.ndarray, test: np.ndarray, ppd: float) -> tuple[np.ndarray, float]:
    """HDR-FLIP of ``test`` against ``ref`` (linear ``[H, W, >=3]``) as the bench computes it
    (:func:`vrneural.bench.metrics.flip_hdr`), with the magma colour map: ``([H, W, 4]`` uint8,
    mean error)."""
    import flip_evaluator

    a = np.ascontiguousarray(np.maximum(np.nan_to_num(ref[..., :3]), 0), np.float32)
    b = np.ascontiguousarray(np.maximum(np.nan_to_num(test[..., :3]), 0), np.float32)
    m, mean, _ = flip_evaluator.evaluate(
        a, b, "HDR", inputsRGB=True, applyMagma=True, parameters={"ppd": float(ppd)}
    )
    rgba = np.full((*m.shape[:2], 4), 255, np.uint8)
    rgba[..., :3] = np.clip(np.round(np.asarray(m, np.float32) * 255), 0, 255)
    return rgba, float(mean)


class FlipWorker:
    """One FLIP job at a time in a spawned worker process."""

    def __init__(self):
        self.pool = None
        self.job = None

    @property
    def busy(self) -> bool:
        return self.job is not None and not self.job.done()

    def submit(self, ref: np.ndarray, test: np.ndarray, ppd: float) -> bool:
        """Start a job unless one is running; whether it started."""
        if self.busy:
            return False
        try:
            import flip_evaluator  # noqa: F401
        except ImportError:
            raise VrnError(
                "the FLIP split view needs flip-evaluator: pip install 'vrneural[metrics]'"
            ) from None
        if self.pool is None:
            import multiprocessing
            from concurrent.futures import ProcessPoolExecutor

            ctx = multiprocessing.get_context("spawn")
            self.pool = ProcessPoolExecutor(max_workers=1, mp_context=ctx)
        self.job = self.pool.submit(flip_map, ref, test, ppd)
        return True

    def result(self, wait: bool = False):
        """``(map, mean)`` of a finished job (once), else None."""
        if self.job is None or (not wait and not self.job.done()):
            return None
        job, self.job = self.job, None
        return job.result()

    def close(self) -> None:
        if self.pool is not None:
            self.pool.shutdown(wait=False, cancel_futures=True)
            self.pool = None
