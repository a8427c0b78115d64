"""``vrneural bench extremes``: every numerical-extreme case of the pipeline, one report.

The cases are pytest tests, ``tests/extremes/test_cases.py`` (marker ``extremes``; the case
functions in ``tests/extremes/*.py``), listed here in :data:`CASES`. Each case either works with
its documented behaviour or is rejected with a one-line error; anything else is a FAIL. This
module runs them with pytest (:func:`run_extremes`; :class:`Collector` turns pytest's reports
into records) and writes ``results.json`` (one record per case: outcome, message, measured
values, seconds), ``results.md`` (the table) and ``f16_error.png`` (histogram of the
f16-vs-f32 relative error). Heavy cases (1M triangles, the largest accepted texture) run in full
size only without ``--quick``. Exit code 1 on any FAIL. The cases are test code: they live in
the source checkout (``pip install -e '.[dev]'``, as ``scripts/setup.sh`` installs), not in the
installed package.
"""

from __future__ import annotations

import sys
import time
from dataclasses import dataclass
from pathlib import Path
from typing import NamedTuple

from vrneural.bench.extremes_report import write_report
from vrneural.bench.report import header, prepare_out
from vrneural.config import Config, opt
from vrneural.errors import VrnError

W, R = "works", "rejected"


class Case(NamedTuple):
    name: str
    group: str
    function: str  #: its function in ``tests/extremes/*.py``
    expect: str  #: ``works`` or ``rejected``
    checks: str  #: what it checks (the report's column)


def _group(group: str, rows: list[tuple]) -> list[Case]:
    """The cases of ``group``: rows of (name, function, expect, checks)."""
    return [Case(name, group, fn, expect, checks) for name, fn, expect, checks in rows]


CASES = [
    *_group("directions", [
        ("grazing_89.99deg", "case_dir_grazing", W, "finite, >= 0, Lipschitz-continuous"),
        ("normal_and_wi=-wo", "case_dir_normal_and_opposite", W, "h fallback (0,0,1)"),
        ("horizon_twin", "case_dir_horizon", W, "tapers to 0, no jump; 0 below"),
        ("horizon_gpu", "case_dir_horizon_gpu", W, "same on the GPU, f32 + f16"),
        ("grazing_gpu", "case_dir_grazing_gpu", W, "GPU vs twin at 89.99 deg"),
        ("terminator", "case_dir_terminator", W, "step <= 1% of peak, 3 modes"),
        ("unnormalized_frames", "case_dir_unnormalized", W, "scaled frames = unit"),
    ]),
    *_group("precision", [
        ("f16_vs_f32", "case_prec_f16_vs_f32", W, "max / p99.9 relative error"),
        ("clamp_1e6_at_1e-4m", "case_prec_clamp", W, "clamped to 65504, finite"),
        ("no_flush_to_zero", "case_prec_no_flush", W, "values >= 2^-14 kept"),
        ("wide_rgba32float", "case_prec_wide_storage", W, "option: cost + error"),
        ("intensity_above_1e6", "case_intensity_limit", R, "scene loader limit"),
    ]),
    *_group("geometry", [
        ("zero_area_3d", "case_geo_zero_area_3d", W, "skipped with a warning"),
        ("zero_area_uv", "case_geo_zero_area_uv", W, "fallback tangent frame"),
        ("slivers_1e-5", "case_geo_sliver", W, "atlas + kernel finite"),
        ("one_triangle", "case_geo_one_triangle", W, "atlas + kernel"),
        ("non_manifold", "case_geo_non_manifold", W, "fin + bow-tie"),
        ("nan_vertex", "case_geo_nan_vertex", R, "make_mesh"),
        ("inf_vertex_obj", "case_geo_inf_vertex_file", R, "load_mesh"),
        ("far_1e5m", "case_geo_far_origin", W, "camera-relative = at origin"),
        ("many_triangles", "case_geo_many_triangles", W, "1M (quick: 20k)"),
        ("far_1e5m_render", "case_set_far_origin_render", W, "image = at origin"),
    ]),
    *_group("settings", [
        ("tex_res_2_kernel", "case_set_kernel_res_2", W, "kernel alone, one block"),
        ("tex_res_2_run", "case_set_tex_res_2", R, "atlas needs R >= 8"),
        ("tex_res_odd", "case_set_tex_res_odd", R, "2x2 blocks"),
        ("tex_res_max", "case_set_tex_res_max", W, "largest accepted (quick: 1024)"),
        ("tex_res_above_max", "case_set_tex_res_above_max", R, "adapter max + 2"),
        ("reuse_N=0", "case_set_reuse_0", W, "update every frame"),
        ("reuse_N=1000", "case_set_reuse_1000", W, "staggered 1/1001"),
        ("lights_0", "case_set_lights_0", W, "black, no MLP work"),
        ("lights_16", "case_set_lights_16", W, "16 lights"),
        ("1_eye_1_frame", "case_set_one_eye_one_frame", W, "minimal run"),
    ]),
    *_group("training", [
        ("btf_all_zeros", "case_train_zeros", W, "finite, loss falls"),
        ("btf_hdr_1e4", "case_train_hdr", W, "finite (linear + log space)"),
        ("btf_nan", "case_train_nan", R, "one-line error"),
        ("lr_floor", "case_train_lr_floor", W, "reaches and keeps lr_min"),
        ("1_epoch", "case_train_one_epoch", W, "one epoch"),
    ]),
]  # fmt: skip

#: the pytest module of the cases, in the source checkout
TESTS = Path(__file__).resolve().parents[2] / "tests" / "extremes" / "test_cases.py"


def case_names(flag: str, value) -> tuple[str, ...]:
    """``--only``: case names or groups of :data:`CASES`, at least one (one-line VrnError)."""
    text = value if isinstance(value, str) else ",".join(map(str, value))
    items = tuple(t.strip() for t in text.split(","))
    groups = ", ".join(sorted({c[1] for c in CASES}))
    if not all(items):
        what = "is empty" if not any(items) else f"= {text!r} has an empty item"
        raise VrnError(f"{flag} {what}; name cases or groups ({groups}), or leave it out")
    bad = sorted(set(items) - {c[0] for c in CASES} - {c[1] for c in CASES})
    if bad:
        raise VrnError(
            f"{flag} = {text!r}: unknown case or group {bad[0]!r}; groups: {groups}; "
            f"cases: {', '.join(c[0] for c in CASES)}"
        )
    return items


@dataclass
class ExtremesConfig(Config):
    """``vrneural bench extremes`` settings."""

    quick: bool = opt(
        False, "small sizes for the heavy cases (1M triangles -> 20k, max texture -> 1024)"
    )
    only: tuple[str, ...] | None = opt(
        None,
        "comma-separated case names or groups to run: "
        f"{', '.join(sorted({c[1] for c in CASES}))} (default: all)",
        items=case_names,
    )
    force: bool = opt(False, "overwrite an existing --out directory")
    progress: bool = opt(True, "show a progress bar (--no-progress: none)")


def selected(only: tuple[str, ...] | None) -> list:
    """The cases ``--only`` names (all of them when it is None)."""
    return CASES if only is None else [c for c in CASES if c[0] in only or c[1] in only]


class Collector:
    """A pytest plugin: keeps the items of the ``names`` cases (in :data:`CASES` order), shows
    a progress bar, and turns each case's reports into its record (:attr:`records`).

    A test fills ``case``, ``group``, ``expect``, ``checks``, ``metrics`` and ``message`` of the
    record it appends to its ``user_properties`` as ``("extreme", record)``; the outcome is
    the expected one when the test passed and ``FAIL`` when it did not (with the message of the
    test's ``pytest.fail``, or ``crash: <exception>``)."""

    def __init__(self, names: set[str] | None = None, progress: bool = False):
        self.names, self.progress, self.records, self.errors = names, progress, {}, []
        self.bar = None

    def pytest_collection_modifyitems(self, config, items):
        keep = [it for it in items if self.names is None or _name(it) in self.names]
        config.hook.pytest_deselected(items=[it for it in items if it not in keep])
        items[:] = keep
        if self.progress:
            from tqdm import tqdm

            self.bar = tqdm(total=len(keep), desc="bench extremes", unit="case")

    def pytest_collectreport(self, report):
        if report.failed:
            self.errors.append(f"{report.nodeid}: {_last_line(report)}")

    def pytest_runtest_logreport(self, report):
        rec = next((v for k, v in report.user_properties if k == "extreme"), None)
        if rec is None:
            return
        if report.when == "call" or (report.failed and "outcome" not in rec):
            rec["seconds"] = report.duration if report.when == "call" else 0.0
            if report.passed:
                rec["outcome"] = rec["expect"]
            elif report.skipped:
                rec["outcome"], rec["message"] = "FAIL", f"skipped: {_last_line(report)}"
            else:
                msg = _last_line(report)
                rec["outcome"] = "FAIL"
                rec["message"] = (
                    msg.removeprefix("Failed: ") if msg.startswith("Failed: ") else f"crash: {msg}"
                )[:400]
            self.records[rec["case"]] = rec
        if report.when == "teardown" and self.bar is not None:
            self.bar.update()

    def pytest_sessionfinish(self):
        if self.bar is not None:
            self.bar.close()


def _name(item) -> str:
    spec = getattr(item, "callspec", None)
    return spec.id if spec is not None else item.name


def _last_line(report) -> str:
    crash = getattr(report.longrepr, "reprcrash", None)
    text = crash.message if crash is not None else str(report.longrepr)
    return (text.strip().splitlines() or ["?"])[-1][:300]


def find_pytest():
    """pytest, once the cases are found (one-line :class:`VrnError` when either is missing)."""
    try:
        import pytest
    except ImportError:
        raise VrnError(
            "the extremes cases are pytest tests and pytest is not installed: install the dev "
            "extra (pip install -e '.[dev]', as scripts/setup.sh does)"
        ) from None
    if not TESTS.is_file():
        raise VrnError(
            f"the extremes cases are tests of the source checkout and {TESTS} is missing: run "
            "this from a clone installed with pip install -e '.[dev]'"
        )
    return pytest


def run_pytest(pytest, cases: list, quick: bool, progress: bool) -> list[dict]:
    """Run ``cases`` with ``pytest`` (quiet: the records are the report); their records in
    order. Ctrl-C stops as it stops any command; a one-line :class:`VrnError` when pytest
    cannot run them."""
    col = Collector({c.name for c in cases}, progress)
    args = [str(TESTS), "-m", "extremes", f"--rootdir={TESTS.parents[2]}", "-p", "no:terminal"]
    args += ["-p", "no:cacheprovider", *([] if quick else ["--extremes-full"])]
    rc = pytest.main(args, plugins=[col])
    if col.errors:
        raise VrnError(f"pytest could not collect the extremes cases: {col.errors[0]}")
    if rc == pytest.ExitCode.INTERRUPTED:
        raise KeyboardInterrupt
    if len(col.records) != len(cases):
        raise VrnError(f"pytest ran {len(col.records)} of {len(cases)} extremes cases (exit {rc})")
    return [col.records[c.name] for c in cases]


class ReportPlugin(Collector):
    """``pytest --extremes-report DIR`` (tests/conftest.py): the bench's report of the cases
    that ran, written into ``DIR`` when the session ends (a new folder, or one of ours, which is
    replaced)."""

    def __init__(self, out: str, quick: bool):
        super().__init__()
        self.out, self.t0 = out, time.perf_counter()
        self.cfg = ExtremesConfig(quick=quick, force=True, progress=False)

    def pytest_sessionfinish(self, session):
        try:
            with prepare_out(self.out, True, "extremes") as root:
                doc = header("extremes", self.cfg)
                doc["records"] = [self.records[c.name] for c in CASES if c.name in self.records]
                write_report(root, doc, self.t0)
        except VrnError as e:
            print(f"--extremes-report: error: {e}", file=sys.stderr)
            session.exitstatus = 4


def run_extremes(cfg: ExtremesConfig, out: str) -> dict:
    """Run the cases, write the report into ``out``; returns the results document."""
    cases = selected(cfg.only)
    pytest = find_pytest()
    with prepare_out(out, cfg.force, "extremes") as root:
        t0 = time.perf_counter()
        doc = header("extremes", cfg)
        doc["records"] = run_pytest(pytest, cases, cfg.quick, cfg.progress)
        return write_report(root, doc, t0)
