"""What the viewer writes: screenshots (``P``: PNG + EXR + the exact settings as JSON, never
over an earlier one), the ``--record`` video of what the window showed, and the split view's
FLIP heat map, computed in a worker process (flip-evaluator holds the GIL for seconds at the
preview size, which would freeze the window)."""

from __future__ import annotations

import json
import os
import subprocess
import sys
from concurrent.futures import ThreadPoolExecutor
from pathlib import Path

import numpy as np

from vrneural.errors import VrnError
from vrneural.outputs import write_json
from vrneural.runtime.output import VideoWriter, write_exr, write_png


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
    (:func:`vrneural.scoring.metrics.flip_hdr`), with the magma colour map: ``([H, W, 4]`` uint8,
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


def write_array(f, a: np.ndarray) -> None:
    """One array on a byte stream: a JSON line (dtype, shape), then its bytes."""
    a = np.asarray(a)
    a = a if a.flags.c_contiguous else a.copy(order="C")  # (ascontiguousarray makes 0-d 1-d)
    f.write((json.dumps({"dtype": a.dtype.str, "shape": a.shape}) + "\n").encode())
    f.write(a.tobytes())
    f.flush()


def read_array(f) -> np.ndarray | None:
    """The next :func:`write_array` array of stream ``f`` (None at its end)."""
    line = f.readline()
    if not line:
        return None
    head = json.loads(line)
    n = int(np.prod(head["shape"])) * np.dtype(head["dtype"]).itemsize
    data = f.read(n)
    if len(data) != n:
        return None
    return np.frombuffer(data, head["dtype"]).reshape(head["shape"])


def serve() -> None:
    """The worker process (``python -m vrneural.viewer.outputs``): per request ``(ppd, ref,
    test)`` on stdin, ``(map, mean)`` on stdout, until stdin closes."""
    inp, out = sys.stdin.buffer, sys.stdout.buffer
    while (ppd := read_array(inp)) is not None:
        ref, test = read_array(inp), read_array(inp)
        m, mean = flip_map(ref, test, float(ppd.reshape(-1)[0]))
        write_array(out, m)
        write_array(out, np.float64(mean))


class FlipWorker:
    """One FLIP job at a time in a worker process (started on first use, fed through pipes:
    no multiprocessing, so scripts need no ``__main__`` guard); a thread waits for the answer."""

    def __init__(self):
        self.proc = None
        self.waiter = None
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
        if self.proc is None or self.proc.poll() is not None:
            self.proc = subprocess.Popen(
                [sys.executable, "-m", "vrneural.viewer.outputs"],
                stdin=subprocess.PIPE,
                stdout=subprocess.PIPE,
            )
            self.waiter = self.waiter or ThreadPoolExecutor(1, thread_name_prefix="flip")
        self.job = self.waiter.submit(self._ask, self.proc, ref, test, ppd)
        return True

    @staticmethod
    def _ask(proc, ref, test, ppd):
        write_array(proc.stdin, np.float64(ppd))
        write_array(proc.stdin, np.asarray(ref, np.float32))
        write_array(proc.stdin, np.asarray(test, np.float32))
        m, mean = read_array(proc.stdout), read_array(proc.stdout)
        if m is None or mean is None:
            raise VrnError("the FLIP worker process stopped (see its message above)")
        return m, float(mean.reshape(-1)[0])

    def result(self, wait: bool = False):
        """``(map, mean)`` of a finished job (once), else None."""
        if self.job is None or (not wait and not self.job.done()):
            return None
        job, self.job = self.job, None
        return job.result()

    def close(self) -> None:
        if self.proc is not None:
            try:
                self.proc.stdin.close()
                self.proc.wait(timeout=10)
            except Exception:  # stuck in a job: stop it
                self.proc.kill()
            self.proc = None
        if self.waiter is not None:
            self.waiter.shutdown(wait=False, cancel_futures=True)
            self.waiter = None


if __name__ == "__main__":
    serve()
