"""The generator: determinism (same seed -> same bytes), value sanity, resume after Ctrl-C."""

import numpy as np
import pytest

import vrneural.btf.render as render
from vrneural.btf import read_btf
from vrneural.btf.config import PRESET_NAMES, PT_PRESET_NAMES
from vrneural.btf.presets import PRESETS
from vrneural.btf.pt_presets import PT_PRESETS
from vrneural.btf.synth import BtfConfig, synthesize
from vrneural.errors import VrnError


def test_the_configs_name_the_presets_the_builders_have():
    """The light config module (CLI start-up) lists the presets without importing them."""
    assert PRESET_NAMES == tuple(sorted(PRESETS))
    assert PT_PRESET_NAMES == tuple(PT_PRESETS)


def _interrupt_after(monkeypatch, cfg, out, views: int) -> str:
    """Synthesise ``cfg`` into ``out``, interrupted (KeyboardInterrupt, what SIGINT does in the
    view loop) after ``views`` views; what the interrupt says (the command line prints it)."""
    real = render.render_view
    calls = {"n": 0}

    def interrupt(*a, **k):
        calls["n"] += 1
        if calls["n"] == views + 1:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(render, "render_view", interrupt)
    with pytest.raises(KeyboardInterrupt) as ei:
        synthesize(cfg, out, progress=False)
    monkeypatch.setattr(render, "render_view", real)
    return str(ei.value)


def _interrupted_after_three_views(tmp_path, monkeypatch):
    """A carpet 8^2 x 7 directions synth interrupted after 3 of its 7 views: ``(config, bytes
    of an uninterrupted run, output)``."""
    cfg = BtfConfig(preset="carpet", res=8, dirs=7, seed=1)
    full = synthesize(cfg, tmp_path / "full.btf", progress=False).read_bytes()
    out = tmp_path / "r.btf"
    said = _interrupt_after(monkeypatch, cfg, out, 3)
    assert said.startswith("after 3/7 views of") and "--resume" in said, said
    return cfg, full, out


def test_same_seed_same_bytes_other_seed_differs(tmp_path):
    cfg = BtfConfig(preset="fabric", res=8, dirs=6, seed=3)
    a = synthesize(cfg, tmp_path / "a.btf", progress=False).read_bytes()
    b = synthesize(cfg, tmp_path / "b.btf", progress=False).read_bytes()
    c = synthesize(
        BtfConfig(preset="fabric", res=8, dirs=6, seed=4), tmp_path / "c.btf", progress=False
    ).read_bytes()
    assert a == b
    assert a != c


@pytest.mark.parametrize("preset", sorted(PRESETS))
def test_values_finite_nonnegative_and_varied(tmp_path, preset):
    b = read_btf(
        synthesize(BtfConfig(preset=preset, res=12, dirs=8), tmp_path / "p.btf", progress=False)
    )
    v = np.asarray(b.values, np.float32)
    assert np.isfinite(v).all() and v.min() >= 0 and v.max() <= 65504
    assert v.max() > 0.01
    # spatially varying: texels of one slice differ; and view-dependent
    assert v[0, 0].std() > 1e-3 * v[0, 0].mean()
    assert not np.allclose(v[:, 0], v[:, -1])
    assert b.meta["generator"]["preset"] == preset and b.meta["convention"] == "cos_inside"


def test_ctrl_c_leaves_a_resumable_partial_and_resume_gives_same_bytes(
    tmp_path, monkeypatch, capsys
):
    cfg, full, out = _interrupted_after_three_views(tmp_path, monkeypatch)
    assert not out.exists()
    assert capsys.readouterr().err == ""  # what was kept rides on the interrupt (one line)
    partial = tmp_path / "r.btf.partial"
    assert partial.exists()
    assert sorted(int(x) for x in (tmp_path / "r.btf.partial.done").read_text().split()) == [
        0,
        1,
        2,
    ]
    synthesize(cfg, out, resume=True, progress=False)
    assert "resuming, 3/7" in capsys.readouterr().err
    assert out.read_bytes() == full
    assert not partial.exists()


def test_resume_with_other_settings_keeps_the_partial_and_names_them(tmp_path, monkeypatch):
    cfg = BtfConfig(preset="carpet", res=8, dirs=7, seed=1)
    out = tmp_path / "r.btf"
    _interrupt_after(monkeypatch, cfg, out, 2)
    partial = tmp_path / "r.btf.partial"
    before = partial.read_bytes()
    other = BtfConfig(preset="carpet", res=10, dirs=7, seed=1)
    with pytest.raises(VrnError, match=r"other settings \(res: 8 there, 10 here\).*--force"):
        synthesize(other, out, resume=True, progress=False)
    assert partial.read_bytes() == before  # the two rendered views are still there
    # --force starts over with the new settings
    b = read_btf(synthesize(other, out, resume=True, progress=False, force=True))
    assert b.resolution == (10, 10) and not partial.exists()


def test_resume_counts_only_valid_finished_views(tmp_path, monkeypatch, capsys):
    """A damaged ``.partial.done`` neither inflates the "resuming, k/N" count nor skips a view
    that was never rendered (an out-of-range index is an error, a repeated one counts once, a
    last line cut short is dropped), and the resumed file is byte-identical."""
    cfg, full, out = _interrupted_after_three_views(tmp_path, monkeypatch)
    done = tmp_path / "r.btf.partial.done"
    assert done.read_text() == "0\n1\n2\n"
    capsys.readouterr()
    done.write_text("0\n1\n2\n999\n")  # out of range for 7 views: was counted as "4/7"
    with pytest.raises(VrnError, match=r"r\.btf\.partial\.done, line 4: view index 999 is out"):
        synthesize(cfg, out, resume=True, progress=False)
    assert "resuming" not in capsys.readouterr().err
    done.write_text("0\n1\n2\n1\n6")  # a repeat, and view 6 (never rendered) cut short
    synthesize(cfg, out, resume=True, progress=False)
    assert "resuming, 3/7 views already done" in capsys.readouterr().err
    assert out.read_bytes() == full  # view 6 was rendered, not skipped
