"""Test tiers. GPU tests carry ``@pytest.mark.gpu``.

The adapter is probed once, in a subprocess with a timeout (a broken driver must not hang the
run). Without an adapter GPU tests skip on a developer machine; under ``CI=true`` the run fails
instead, and it also fails when the adapter is not lavapipe/llvmpipe (``EXPECT_LAVAPIPE``,
default on in CI), so GPU tests can never silently skip in CI.
"""

from __future__ import annotations

import json
import os
import subprocess
import sys

import numpy as np
import pytest
from hypothesis import HealthCheck, settings

CI = os.environ.get("CI", "").lower() in ("1", "true", "yes")
EXPECT_LAVAPIPE = os.environ.get("EXPECT_LAVAPIPE", "1" if CI else "0") not in ("", "0")
os.environ.setdefault("XDG_RUNTIME_DIR", "/tmp")

settings.register_profile(
    "ci", max_examples=25, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.register_profile(
    "dev", max_examples=50, deadline=None, suppress_health_check=[HealthCheck.too_slow]
)
settings.load_profile(os.environ.get("HYPOTHESIS_PROFILE", "ci" if CI else "dev"))

_PROBE = (
    "import json; from vrneural.gpu import adapter_summary; "
    "print(json.dumps(adapter_summary().to_dict()))"
)


def _probe_adapter() -> tuple[dict | None, str]:
    try:
        r = subprocess.run(
            [sys.executable, "-c", _PROBE], capture_output=True, text=True, timeout=120
        )
    except subprocess.TimeoutExpired:
        return None, "adapter probe timed out after 120 s"
    if r.returncode != 0:
        tail = (r.stderr.strip().splitlines() or ["?"])[-1]
        return None, tail
    return json.loads(r.stdout.strip().splitlines()[-1]), ""


ADAPTER, ADAPTER_ERR = _probe_adapter()


def pytest_addoption(parser):
    g = parser.getgroup("extremes", "the extremes cases (tests/extremes, vrneural bench extremes)")
    g.addoption(
        "--extremes-full",
        action="store_true",
        help="run the extremes cases at full size (default: the --quick sizes)",
    )
    g.addoption(
        "--extremes-report",
        metavar="DIR",
        help="write results.json, results.md and f16_error.png of the extremes cases that ran "
        "into DIR (a new folder, or one of ours: replaced), as vrneural bench extremes does",
    )


def pytest_configure(config):
    out = config.getoption("extremes_report")
    if out:
        from vrneural.bench.extremes import ReportPlugin

        quick = not config.getoption("extremes_full")
        config.pluginmanager.register(ReportPlugin(out, quick), "extremes-report")


def pytest_report_header(config):
    if ADAPTER:
        return f"wgpu adapter: {ADAPTER['name']} ({ADAPTER['adapter_type']}, {ADAPTER['backend']})"
    return f"wgpu adapter: none ({ADAPTER_ERR})"


def pytest_collection_modifyitems(config, items):
    gpu_items = [it for it in items if "gpu" in it.keywords]
    if not gpu_items:
        return
    if ADAPTER is None:
        if CI:
            raise pytest.UsageError(f"CI=true but no wgpu adapter was found: {ADAPTER_ERR}")
        skip = pytest.mark.skip(reason=f"no wgpu adapter ({ADAPTER_ERR})")
        for it in gpu_items:
            it.add_marker(skip)
    elif EXPECT_LAVAPIPE and "llvmpipe" not in ADAPTER["name"].lower():
        raise pytest.UsageError(f"EXPECT_LAVAPIPE is set but the adapter is {ADAPTER['name']!r}")


@pytest.fixture(autouse=True)
def _numpy_strict():
    """Floating-point errors raise in tests (underflow excepted: f16 rounding underflows)."""
    with np.errstate(all="raise", under="ignore"):
        yield


@pytest.fixture
def rng():
    """A seeded generator; each test gets the same stream."""
    return np.random.default_rng(1234)


@pytest.fixture(scope="session")
def adapter():
    return ADAPTER
