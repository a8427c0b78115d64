"""The docs page "Python API" (docs/python-api.md) runs as written (each ```python block, in
order)."""

from __future__ import annotations

import re
from pathlib import Path

import numpy as np
import pytest

from vrneural.btf.dirs import direction_set
from vrneural.btf.format import write_btf

ROOT = Path(__file__).resolve().parent.parent


PAGE = ROOT / "docs" / "python-api.md"


def _blocks() -> list[str]:
    text = PAGE.read_text()
    assert text.startswith("# Python API\n")
    return re.findall(r"```python\n(.*?)```", text, flags=re.S)


def test_the_page_has_its_three_recipes():
    blocks = _blocks()
    assert len(blocks) == 3
    assert "predict_slice" in blocks[0] and "evaluate" in blocks[1] and "Renderer" in blocks[2]


@pytest.fixture
def workdir(tmp_path, monkeypatch):
    """An empty folder but for a small ``leather.btf`` (the recipes find the bundled packs
    from anywhere)."""
    d = direction_set(3)
    vals = np.random.default_rng(0).uniform(0.01, 0.3, (3, 3, 8, 8, 3)).astype(np.float32)
    write_btf(tmp_path / "leather.btf", vals, d, d, {"name": "leather"})
    monkeypatch.chdir(tmp_path)
    return tmp_path


@pytest.mark.parametrize("k", [0, 1])
def test_numpy_recipes(workdir, k, capsys):
    exec(compile(_blocks()[k], f"docs/python-api.md python block {k}", "exec"), {})
    assert capsys.readouterr().out.strip()


@pytest.mark.gpu
def test_frames_in_memory_recipe(workdir, adapter, capsys):
    ns: dict = {}
    exec(compile(_blocks()[2], "docs/python-api.md python block 2", "exec"), ns)
    assert ns["left"].shape[-1] == 4 and np.isfinite(ns["left"]).all()
    assert float(ns["left"][..., :3].max()) > 0  # something was lit
    assert ns["radiance"].shape[0] == ns["radiance"].shape[1]
