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
from pathlib import Path

from vrneural.bench.configs import CASES, ExtremesConfig
from vrneural.bench.extremes_report import write_report
from vrneural.bench.report import header, prepare_out
from vrneural.errors import VrnError

#: the pytest module of the cases, in the source checkout
TESTS = Path(__file__).resolve().parents[2] / "tests" / "extremes" / "test_cases.py"


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
