"""The BTF file (``.btf``): ``values[light, view, y, x, rgb]`` float16, memory-mapped.

Container: :mod:`vrneural.formats.container` with magic ``b"VRNBTF"``. Arrays:

- ``values``      ``[L, V, H, W, 3]`` float16, BTF value (docs/conventions.md section 2: outgoing
  radiance per unit irradiance measured perpendicular to ``wi``; cos(theta_i) is inside)
- ``light_dirs``  ``[L, 3]`` float32 unit vectors, local frame, pointing away from the surface
- ``view_dirs``   ``[V, 3]`` float32 unit vectors
- ``height``      optional ``[N, N]`` float32: the tile's height field (version 2 files only),
  the height of the top surface seen from straight above at grid cell centres
  ``((j + 0.5) / N, (i + 0.5) / N)``, in UV units (fractions of the tile width) above the
  reference plane (its mean is 0: the plane the rectified slices are taken on). For parallax
  and displacement; a file without it is written as version 1, byte for byte as before.

Header: ``name``, ``convention`` ("cos_inside"), ``generator`` (config dict or import source),
``seed``, ``texel_size_mm`` (optional), plus anything the writer adds (except the keys in
:data:`RESERVED_KEYS`, which the format and its container set themselves). The texel ``(x, y)``
has its centre at material UV ``((x + 0.5) / W, (y + 0.5) / H)``; tiles repeat (wrap) in both axes.
"""

from __future__ import annotations

import contextlib
import sys
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np
from tqdm import tqdm

from vrneural.btf.config import RENDER_BEFORE
from vrneural.errors import VrnError
from vrneural.formats.container import ContainerWriter, read_container, write_container
from vrneural.formats.f16 import F16_MAX
from vrneural.interrupt import interrupt_saying
from vrneural.outputs import partial_path

BTF_MAGIC = b"VRNBTF"
BTF_VERSION = 1
#: the version of a file that carries a height field; readers take both
BTF_VERSION_HEIGHT = 2
BTF_VERSIONS = (BTF_VERSION, BTF_VERSION_HEIGHT)
CONVENTION = "cos_inside"
#: header keys a writer's ``meta`` may not set: the container's own (array table, file size,
#: per-array CRC32s, the unfinished-write mark) and the BTF convention
RESERVED_KEYS = ("array_crc32", "arrays", "convention", "file_size", "partial")


@dataclass
class Btf:
    """An opened BTF. ``values`` is a read-only memory map; nothing is loaded until indexed."""

    path: Path | None
    values: np.ndarray  # [L, V, H, W, 3] float16
    light_dirs: np.ndarray  # [L, 3] float32
    view_dirs: np.ndarray  # [V, 3] float32
    meta: dict = field(default_factory=dict)
    height: np.ndarray | None = None  # [N, N] float32, UV units (version 2), or None

    @property
    def shape(self) -> tuple[int, int, int, int]:
        """``(L, V, H, W)``."""
        return tuple(self.values.shape[:4])  # type: ignore[return-value]

    @property
    def resolution(self) -> tuple[int, int]:
        """``(H, W)`` texels."""
        return int(self.values.shape[2]), int(self.values.shape[3])

    def slice(self, light: int, view: int) -> np.ndarray:
        """One ``(light, view)`` slice ``[H, W, 3]`` as float32 (reads only that slice)."""
        return np.asarray(self.values[light, view], dtype=np.float32)


def _check_not_empty(path, L: int, V: int, H: int, W: int) -> None:
    if min(L, V, H, W) < 1:
        raise VrnError(
            f"{path}: an empty BTF ({L} lights x {V} views x {H}x{W} texels); lights, views, "
            "height and width must each be at least 1"
        )


def _header(path, meta: dict) -> dict:
    """The header a writer stores: the convention plus ``meta``, which may not set a reserved
    key (one would be overwritten, dropped on read, or mark a finished file as unfinished).
    ``convention`` equal to :data:`CONVENTION` is let through (a read BTF's ``meta`` has it)."""
    if "convention" in meta and meta["convention"] != CONVENTION:
        raise VrnError(
            f"{path}: meta key 'convention' = {meta['convention']!r} is not allowed: BTF values "
            f"are always {CONVENTION!r} (cos(theta_i) inside); drop the key"
        )
    bad = sorted(k for k in meta if k in RESERVED_KEYS and k != "convention")
    if bad:
        raise VrnError(
            f"{path}: meta key {bad[0]!r} is reserved by the BTF format (reserved: "
            f"{', '.join(RESERVED_KEYS)}); store it under another name"
        )
    return {"convention": CONVENTION, **meta}


def _validate(path, values, light_dirs, view_dirs, height=None) -> None:
    if values.ndim != 5 or values.shape[4] != 3:
        raise VrnError(f"{path}: values has shape {list(values.shape)}, expected [L, V, H, W, 3]")
    _check_not_empty(path, *values.shape[:4])
    L, V = values.shape[:2]
    if light_dirs.shape != (L, 3):
        raise VrnError(f"{path}: light_dirs has shape {list(light_dirs.shape)}, expected [{L}, 3]")
    if view_dirs.shape != (V, 3):
        raise VrnError(f"{path}: view_dirs has shape {list(view_dirs.shape)}, expected [{V}, 3]")
    if height is not None:
        if height.ndim != 2 or height.shape[0] != height.shape[1] or height.shape[0] < 2:
            raise VrnError(
                f"{path}: height has shape {list(height.shape)}, expected a square [N, N], N >= 2"
            )
        if not np.isfinite(np.asarray(height, np.float64)).all():
            raise VrnError(f"{path}: the height field contains NaN or Inf")
    for name, d in (("light_dirs", light_dirs), ("view_dirs", view_dirs)):
        n = np.linalg.norm(np.asarray(d, np.float64), axis=1)
        if not np.all(np.isfinite(n)) or np.abs(n - 1).max(initial=0) > 1e-3:
            raise VrnError(f"{path}: {name} are not unit vectors")


def read_btf(path) -> Btf:
    """Open and validate a ``.btf`` file (magic, version, truncation, shapes)."""
    header, arrays, _ = read_container(
        path, BTF_MAGIC, BTF_VERSIONS, what="BTF file", verify_crc=False
    )
    missing = {"values", "light_dirs", "view_dirs"} - set(arrays)
    if missing:
        raise VrnError(f"{path}: BTF file lacks array(s) {sorted(missing)}")
    values = arrays["values"]
    if values.dtype != np.float16:
        raise VrnError(f"{path}: values are {values.dtype}, expected float16")
    height = arrays.get("height")
    if height is not None and height.dtype != np.float32:
        raise VrnError(f"{path}: height is {height.dtype}, expected float32")
    _validate(path, values, arrays["light_dirs"], arrays["view_dirs"], height)
    meta = {k: v for k, v in header.items() if k not in ("arrays", "file_size", "array_crc32")}
    return Btf(
        Path(path),
        values,
        np.asarray(arrays["light_dirs"]),
        np.asarray(arrays["view_dirs"]),
        meta,
        None if height is None else np.asarray(height),
    )


def write_btf(
    path,
    values: np.ndarray,
    light_dirs: np.ndarray,
    view_dirs: np.ndarray,
    meta: dict,
    height: np.ndarray | None = None,
) -> Path:
    """Write an in-memory BTF atomically (values become float16, clamped to its range);
    with a ``height`` field ``[N, N]`` (UV units) the file is version 2."""
    values = np.asarray(values)
    light_dirs = np.asarray(light_dirs, np.float32)
    view_dirs = np.asarray(view_dirs, np.float32)
    height = None if height is None else np.asarray(height, np.float32)
    _validate(path, values, light_dirs, view_dirs, height)
    if not np.isfinite(values).all():
        raise VrnError(f"{path}: BTF values contain NaN or Inf")
    header = _header(path, meta)
    v16 = np.clip(values, 0, F16_MAX).astype(np.float16)
    arrays = {"values": v16, "light_dirs": light_dirs, "view_dirs": view_dirs}
    if height is not None:
        arrays["height"] = height
    version = BTF_VERSION if height is None else BTF_VERSION_HEIGHT
    return write_container(path, BTF_MAGIC, version, header, arrays)


def check_partial_settings(path, generator: dict) -> None:
    """Refuse to continue the interrupted ``<path>.partial`` where it was made with other
    settings, naming them (``--force`` starts over): the hours already rendered are never
    thrown away silently."""
    partial = partial_path(path)
    if not partial.exists():
        return
    try:
        old = read_container(partial, BTF_MAGIC, BTF_VERSIONS, "partial BTF", False, True)[0]
    except VrnError as e:
        raise VrnError(f"{e}; pass --force instead of --resume to start over") from None
    have = old.get("generator", {})
    if have.get("config") == "RenderConfig":  # a render from before a field was added
        have = RENDER_BEFORE | have
        if "scene" not in have:  # from before the scene's fingerprint: nothing to check it by
            have["scene"] = generator.get("scene")
    diff = [
        f"{k}: {have.get(k)!r} there, {v!r} here" for k, v in generator.items() if have.get(k) != v
    ]
    if diff:
        raise VrnError(
            f"{partial}: the interrupted run used other settings ({'; '.join(diff)}); rerun with "
            "its settings to continue it, or pass --force instead of --resume to start over"
        )


class BtfWriter:
    """Stream a large BTF to disk one ``(light, view)`` slice at a time; resumable.

    Data goes to ``<path>.partial``; :meth:`finalize` renames it into place. With
    ``resume=True`` an identical unfinished write is reopened (see ``done`` for finished views).
    The caller marks progress with :meth:`mark_done` (per view index; kept in a sidecar file).
    A ``height`` field ``[N, N]`` (UV units) makes it a version 2 file.
    """

    def __init__(
        self,
        path,
        light_dirs: np.ndarray,
        view_dirs: np.ndarray,
        resolution: tuple[int, int],
        meta: dict,
        resume: bool = False,
        height: np.ndarray | None = None,
    ):
        L, V = len(light_dirs), len(view_dirs)
        H, W = resolution
        _check_not_empty(path, L, V, H, W)
        if resume and meta.get("generator"):  # what differs, before the container refuses it
            check_partial_settings(path, meta["generator"])
        header = _header(path, meta)
        specs = {
            "values": ((L, V, H, W, 3), "float16"),
            "light_dirs": ((L, 3), "float32"),
            "view_dirs": ((V, 3), "float32"),
        }
        version = BTF_VERSION
        if height is not None:
            height = np.asarray(height, np.float32)
            if height.ndim != 2 or height.shape[0] != height.shape[1]:
                raise VrnError(f"{path}: height has shape {list(height.shape)}, expected [N, N]")
            specs["height"] = (height.shape, "float32")
            version = BTF_VERSION_HEIGHT
        self.path = path  #: the output, as given
        self._w = ContainerWriter(path, BTF_MAGIC, version, header, specs, resume=resume)
        self.partial = self._w.partial  #: the file being written (``<path>.partial``)
        self.resumed = self._w.resumed  #: True when an identical unfinished write was reopened
        self.progress_file = self._w.partial.with_name(self._w.partial.name + ".done")
        if not self._w.resumed:
            self._w.array("light_dirs")[:] = light_dirs
            self._w.array("view_dirs")[:] = view_dirs
            if height is not None:
                self._w.array("height")[:] = height
            self.progress_file.unlink(missing_ok=True)
        self.values = self._w.array("values")
        self.done: set[int] = set()  #: view indices already written (from the sidecar)
        if self._w.resumed and self.progress_file.exists():
            self.done = self._read_progress(V)

    def _read_progress(self, n_views: int) -> set[int]:
        """The finished views listed in the sidecar (one index per line, blank lines ignored).

        A line that is not an index in ``0..n_views-1`` is a one-line error naming the file and
        the line (the file is left as it is). A repeated index is harmless (that view's data was
        written either way) and counts once. An unterminated last line may be a write cut short
        (``"1"`` of ``"12"``), so it is dropped and the file rewritten without it: that view is
        only done again, and the next index appended cannot run into it.
        """
        f = self.progress_file
        fix = (
            "remove that line (a view missing from this list is only done again) or pass "
            "--force instead of --resume to start over"
        )
        try:
            text = f.read_bytes().decode("ascii", errors="replace")
        except OSError as e:
            raise VrnError(
                f"{f}: cannot read the list of finished views ({e.strerror or e})"
            ) from None
        lines = text.split("\n")
        cut = lines.pop()  # "" when the file ends with a newline
        done: set[int] = set()
        for n, line in enumerate(lines, 1):
            t = line.strip()
            if not t:
                continue
            if not (t.isascii() and t.isdigit()):
                shown = repr(t if len(t) <= 40 else t[:40] + "...")
                raise VrnError(
                    f"{f}, line {n}: {shown} is not a view index (one integer 0..{n_views - 1} "
                    f"per line expected); {fix}"
                )
            v = int(t)
            if v >= n_views:
                raise VrnError(
                    f"{f}, line {n}: view index {v} is out of range: the BTF has {n_views} "
                    f"views (0..{n_views - 1}); {fix}"
                )
            done.add(v)
        if cut.strip():
            try:
                f.write_text("".join(f"{v}\n" for v in sorted(done)))
            except OSError as e:
                raise VrnError(
                    f"{f}: cannot rewrite the list of finished views ({e.strerror})"
                ) from None
        return done

    def import_views(self, read, nonfinite, src, crop: str, progress: bool = True) -> Path:
        """Write every view not yet done from ``read(li, v) -> rgb [H, W, 3]`` float32, clamped
        into the float16 range [0, F16_MAX] (a progress bar of views), and :meth:`finalize` the
        file. A slice with a non-finite value discards the partial file and raises a VrnError
        that starts with ``nonfinite(li, v, rgb)``; a Ctrl-C says how to resume and is raised
        again. Then one line on stderr per kind of value clamped (naming ``src``), and a warning
        for an odd size, whose advice says to crop ``crop``."""
        L, V, H, W = self.values.shape[:4]
        name = self.partial.name.removesuffix(".partial")
        neg = huge = 0  # values clamped: negative, above F16_MAX
        bar = tqdm(total=V, initial=len(self.done), desc="import views", unit="view",
                   disable=not progress)  # fmt: skip
        try:
            for v in range(V):
                if v in self.done:
                    continue
                for li in range(L):
                    rgb = read(li, v)
                    if not np.isfinite(rgb).all():  # --resume would stop here again
                        bar.close()
                        self.discard()
                        out = self.partial.with_name(name)
                        was = "left as it was" if out.exists() else "not created"
                        raise VrnError(
                            f"{nonfinite(li, v, rgb)}; nothing was written (no .partial; "
                            f"{name} {was})"
                        )
                    rgb = np.asarray(rgb, np.float32)
                    neg, huge = neg + int((rgb < 0).sum()), huge + int((rgb > F16_MAX).sum())
                    self.values[li, v] = np.clip(rgb, 0.0, F16_MAX).astype(np.float16)
                self.mark_done(v)
                bar.update(1)
        except KeyboardInterrupt as e:
            bar.close()
            raise interrupt_saying(
                f"before {self.partial.with_name(name)} was complete; rerun with --resume to "
                "continue",
                e,
            ) from None
        bar.close()
        if neg:
            print(f"{src}: clamped {neg} negative values to 0", file=sys.stderr)
        if huge:
            print(
                f"{src}: clamped {huge} values above {F16_MAX:g} (the float16 maximum) to "
                f"{F16_MAX:g}",
                file=sys.stderr,
            )
        if H % 2 or W % 2:
            print(
                f"warning: {self.path}: {H}x{W} texels, odd: packs shade 2x2 blocks, so teach, "
                f"distill and eval refuse it; crop {crop} to an even size",
                file=sys.stderr,
            )
        return self.finalize()

    def put_view(self, v: int, view: np.ndarray) -> None:
        """Store rendered view ``v`` (every light, ``[L, H, W, 3]``), clamped into the float16
        range, and mark it done; a non-finite value is an internal error (a renderer's bug)."""
        if not np.isfinite(view).all():
            raise VrnError(f"internal error: non-finite BTF values rendered at view {v}")
        self.values[:, v] = np.clip(view, 0.0, F16_MAX).astype(np.float16)
        self.mark_done(v)

    @contextlib.contextmanager
    def keep_on_interrupt(self, out):
        """A Ctrl-C in the block keeps the views written so far in the ``.partial`` and is
        raised again carrying how to continue (``--resume``; the command line prints it)."""
        try:
            yield
        except KeyboardInterrupt as e:
            self.values.flush()
            raise interrupt_saying(
                f"after {len(self.done)}/{self.values.shape[1]} views of {out}; partial data "
                f"kept in {self.partial}; rerun the same command with --resume to continue",
                e,
            ) from None

    def mark_done(self, view: int) -> None:
        """Flush data and record view index ``view`` as complete."""
        self.values.flush()
        with open(self.progress_file, "a") as f:
            f.write(f"{view}\n")
        self.done.add(view)

    def discard(self) -> None:
        """Remove the unfinished files: for a source that cannot be converted, whose
        ``--resume`` would only stop at the same place again."""
        if hasattr(self, "values"):
            del self.values
        self.partial.unlink(missing_ok=True)
        self.progress_file.unlink(missing_ok=True)

    def finalize(self) -> Path:
        self.values.flush()
        del self.values
        p = self._w.finalize()
        self.progress_file.unlink(missing_ok=True)
        return p
