"""Shared output of the timing and trade-off benchmarks: ``results.json`` (adapter, package
versions, resolved config, one record per configuration), ``results.md`` (tables) and PNG plots,
all written atomically into ``--out DIR``: new, empty, or this bench's own earlier output with
``--force`` (see :class:`vrneural.outputs.OutputDir`).
"""

from __future__ import annotations

import contextlib
import time
from collections.abc import Iterator
from pathlib import Path

from vrneural.atlas.config import MIN_RESOLUTION
from vrneural.config import config_dict, int_items
from vrneural.errors import VrnError, check_range
from vrneural.outputs import OutputDir, atomic_path, write_json
from vrneural.presentation import pyplot, save_png, table  # noqa: F401 (rp.save_png, rp.table)
from vrneural.runtime.config import max_texture_res
from vrneural.runtime.run import percentiles
from vrneural.versions import package_versions


@contextlib.contextmanager
def prepare_out(out: str | Path, force: bool, bench: str) -> Iterator[Path]:
    """Validate and (re)create the output directory of ``vrneural bench <bench>`` for the
    block, sealed when it ends (see :class:`vrneural.outputs.OutputDir`). Cached packs under
    ``packs/`` survive a ``--force`` rerun (they are keyed by their training config)."""
    with OutputDir(out, f"bench {bench}", force=force, keep=("packs",)) as od:
        yield od.open()


def stats(x) -> dict:
    """``{median, p95, p99, mean, max}`` of a sequence of numbers (ms); zeros for none."""
    return percentiles(x) or dict.fromkeys(("median", "p95", "p99", "mean", "max"), 0.0)


def header(bench: str, cfg) -> dict:
    """The common head of every ``results.json``: bench name, adapter, versions, ``cfg``
    (resolved: the values the run used)."""
    from vrneural.gpu.device import adapter_summary

    return {
        "bench": bench,
        "adapter": adapter_summary().to_dict(),
        "versions": package_versions(),
        "config": config_dict(cfg),
        "started": time.strftime("%Y-%m-%dT%H:%M:%SZ", time.gmtime()),
        "records": [],
    }


def adapter_line(doc: dict) -> str:
    a = doc["adapter"]
    cpu = " (CPU adapter: absolute times are not GPU times; read ratios)" if a["is_cpu"] else ""
    return f"Adapter: **{a['name']}**, {a['backend']}{cpu}."


def record_table(records: list[dict], columns: list[tuple]) -> list[str]:
    """:func:`table` with a row per record: ``columns`` are ``(header, field)``, ``field`` a key
    (``"frame_ms.median"``: a nested one) or a function of the record."""

    def get(r, field):
        if callable(field):
            return field(r)
        for k in field.split("."):
            r = r[k]
        return r

    return table([h for h, _ in columns], [[get(r, f) for _, f in columns] for r in records])


def figure(w: float = 6.4, h: float = 4.0, ncols: int = 1, sharey: bool = False):
    """A matplotlib (Agg) figure and its ``ncols`` axes, as a list."""
    fig, axes = pyplot().subplots(
        1, ncols, figsize=(w, h), squeeze=False, sharey=sharey, layout="constrained"
    )
    return fig, list(axes[0])


def plain_log_ticks(axis) -> None:
    """Plain-number labels (``20``, ``30``, not ``2 x 10^1``) on a log ``axis`` (``ax.xaxis``,
    call after plotting): every integer multiple of the decade when the data span less than a
    factor 3, else 1, 2, 5 per decade; no minor labels."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter

    lo, hi = sorted(axis.get_view_interval())
    narrow = lo > 0 and hi / lo < 3.0
    subs = tuple(float(k) for k in range(1, 10)) if narrow else (1.0, 2.0, 5.0)
    axis.set_major_locator(LogLocator(subs=subs))
    axis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    axis.set_minor_formatter(NullFormatter())


def finish(root: Path, doc: dict, md: list[str], t0: float, plots=()) -> dict:
    """Draw ``plots`` (``(file, alt text, fn(doc, path))``: each shown under ``md``), stamp the
    run time, write ``results.json`` and ``results.md`` (``root`` is sealed when
    :func:`prepare_out`'s block ends)."""
    for name, alt, draw in plots:
        draw(doc, root / name)
        md = [*md, "", f"![{alt}]({name})"]
    doc["total_seconds"] = time.perf_counter() - t0
    md = [*md, "", f"Run time {doc['total_seconds']:.0f} s. Raw records: results.json."]
    write_json(root / "results.json", doc)
    with atomic_path(root / "results.md") as tmp:
        tmp.write_text("\n".join(md) + "\n")
    return doc


def texture_res_range() -> tuple[int, int]:
    """``[lo, hi]`` of a radiance texture side on this adapter (the same bounds as `run`)."""
    from vrneural.gpu.device import adapter_summary

    return MIN_RESOLUTION, max_texture_res(adapter_summary())


def check_texture_res(value: int, field: str = "--texture-res") -> int:
    """One radiance texture side: in :func:`texture_res_range` and even (one-line VrnError)."""
    check_range(field, value, *texture_res_range())
    if value % 2:
        raise VrnError(f"{field} = {value} must be even (2x2 blocks)")
    return value


def texture_list(value, field: str = "--texture-res") -> tuple[int, ...]:
    """Radiance texture sides: each in :func:`texture_res_range` and even (one-line VrnError);
    the adapter's bound is why a list field checks it here, not when its config is built."""
    return int_items(field, value, *texture_res_range(), even=True)


#: under the tables of the frame benches whose FPS column is ``1000 / mean frame ms``
FPS_NOTE = (
    "FPS: 1000 / the mean frame ms (wall clock incl. GPU wait), so one slow frame lowers it; "
    "the median and p99 frame ms are beside it."
)
