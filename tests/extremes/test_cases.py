"""Every case of ``vrneural bench extremes`` (:data:`vrneural.bench.configs.CASES`), one test
each, marked ``extremes``: a case that should work returns its measured values with ``ok``
true; one that should be rejected raises a one-line :class:`VrnError`. The suite runs them at
the ``--quick`` sizes; ``--extremes-full`` runs the full sizes and ``--extremes-report DIR``
writes the bench's report (``pytest -m extremes --extremes-report DIR``).

Each test appends its record (``("extreme", record)``) to its ``user_properties``, which
:class:`vrneural.bench.extremes.Collector` turns into the report's rows."""

from __future__ import annotations

import re

import pytest

from extremes import geometry, precision, settings, shading, terminator, training
from vrneural.bench.configs import CASES, R
from vrneural.errors import VrnError

MODULES = (shading, terminator, precision, geometry, settings, training)
#: what a rejection must name, beyond being one line (case -> regular expression)
MESSAGES = {
    "inf_vertex_obj": r"inf\.obj",
    "tex_res_above_max": r"--texture-res",
    "btf_nan": r"nan\.btf: .*NaN/Inf entries \(first at .*\[1, 2, 3, 4, 0\]",
    "nan_vertex": r"NaN/Inf",
}
#: cases that run on the GPU (marked ``gpu``: skipped without an adapter, as every GPU test)
GPU_GROUPS = {"directions", "precision", "geometry", "settings"}
CPU_CASES = {
    "grazing_89.99deg",
    "normal_and_wi=-wo",
    "horizon_twin",
    "intensity_above_1e6",
    "nan_vertex",
    "inf_vertex_obj",
}


def _params():
    for c in CASES:
        marks = [pytest.mark.extremes]
        if c.group in GPU_GROUPS and c.name not in CPU_CASES:
            marks.append(pytest.mark.gpu)
        yield pytest.param(c, id=c.name, marks=marks)


@pytest.fixture
def extremes_quick(request) -> bool:
    return not request.config.getoption("extremes_full")


@pytest.mark.parametrize("case", list(_params()))
def test_case(case, extremes_quick, request):
    rec = {"case": case.name, "group": case.group, "expect": case.expect, "metrics": {}}
    rec.update(message="", checks=case.checks)
    request.node.user_properties.append(("extreme", rec))
    fn = next(getattr(m, case.function) for m in MODULES if hasattr(m, case.function))
    try:
        m = fn(extremes_quick)
    except VrnError as e:
        rec["message"] = msg = str(e)
        if case.expect != R:
            pytest.fail(f"unexpected rejection: {msg}")
        assert "\n" not in msg and 0 < len(msg) < 400, msg
        assert re.search(MESSAGES.get(case.name, ""), msg), msg
        return
    if case.expect == R:
        pytest.fail("accepted, but the documented behaviour is a rejection")
    rec["metrics"] = {k: v for k, v in m.items() if k not in ("ok", "note")}
    rec["message"] = str(m.get("note", ""))
    if not m.get("ok", False):
        pytest.fail(rec["message"] or "the documented behaviour did not hold")
