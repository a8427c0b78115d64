"""`vrneural btf ...`: happy paths and one-line errors (exit 2) that never touch existing files."""

import json
import subprocess
import sys

import numpy as np
import pytest

from vrneural.btf import direction_set, read_btf, write_btf
from vrneural.btf.identity import btf_fingerprint
from vrneural.cli import main


def _vrn(*args, timeout=300):
    return subprocess.run(
        [sys.executable, "-m", "vrneural", *args], capture_output=True, text=True, timeout=timeout
    )


@pytest.fixture(scope="module")
def small_btf(tmp_path_factory):
    out = tmp_path_factory.mktemp("btf") / "leather.btf"
    r = _vrn(
        "btf",
        "synth",
        "--preset",
        "leather",
        "--res",
        "8",
        "--dirs",
        "6",
        "--seed",
        "0",
        "-o",
        str(out),
        "--no-progress",
    )
    assert r.returncode == 0, r.stderr
    return out


def test_synth_writes_btf_and_config(small_btf):
    b = read_btf(small_btf)
    assert b.shape == (6, 6, 8, 8)
    cfg = json.loads(small_btf.with_name("leather.btf.config.json").read_text())
    assert cfg["config"] == "BtfConfig" and cfg["preset"] == "leather" and cfg["res"] == 8
    assert cfg["grid"] == 64  # resolved: 2 x res, at least 64


def test_info_text_and_json(small_btf, capsys):
    assert main(["btf", "info", str(small_btf)]) == 0
    out = capsys.readouterr().out
    assert "6 lights x 6 views x 8x8" in out and "leather" in out
    assert "grid 0 = auto: the heightfield was 64^2" in out  # as the sidecar says, not just 0
    assert main(["btf", "info", str(small_btf), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    v = np.asarray(read_btf(small_btf).values, np.float32)
    assert info["shape"] == {"lights": 6, "views": 6, "height": 8, "width": 8, "channels": 3}
    assert info["value_max"] == pytest.approx(float(v.max()))
    assert info["value_min"] == pytest.approx(float(v.min()))
    assert info["meta"]["name"] == "leather" and info["size_bytes"] > v.nbytes // 2


def test_show_writes_png(small_btf, tmp_path, capsys):
    import imageio.v3 as iio

    out = tmp_path / "sheet.png"
    assert main(["btf", "show", str(small_btf), "-o", str(out), "--texel", "1", "2"]) == 0
    img = iio.imread(out)
    assert img.ndim == 3 and img.shape[0] > 500 and img.std() > 5
    # NaN values: `info` warned, `show` drew them without a word
    nan = tmp_path / "nan.btf"
    nan.write_bytes(small_btf.read_bytes())
    offset = read_btf(nan).values.offset  # the first value (write_btf refuses NaN)
    with open(nan, "r+b") as f:
        f.seek(offset)
        f.write(np.array([np.nan], np.float16).tobytes())
    from vrneural.btf.sheet import BtfWarning

    with pytest.warns(BtfWarning, match="nan.btf: 1 NaN/Inf values"):
        assert main(["btf", "show", str(nan), "-o", str(tmp_path / "nan.png")]) == 0


def test_show_several_files_writes_a_gallery(small_btf, tmp_path, vrn_inproc):
    """`btf show A B -o g.png`: one row per file, one column per pair, each panel the slice
    nearest to its pair (of that file's own directions); --texel is one file's option."""
    import imageio.v3 as iio
    import matplotlib.pyplot as plt

    from vrneural.btf.sheet import PAIRS, gallery_figure, nearest, pair_slices, tonemap

    d = direction_set(8)
    other = write_btf(
        tmp_path / "ramp.btf",
        np.linspace(0.01, 1, 8 * 8 * 4 * 4 * 3, dtype=np.float32).reshape(8, 8, 4, 4, 3),
        d,
        d,
        {"name": "ramp"},
    )
    a, b = read_btf(small_btf), read_btf(other)
    for btf in (a, b):
        got = pair_slices(btf)
        assert len(got) == len(PAIRS)  # pairs sharing a slice keep their own columns
        for (li, vi), (_, (tl, pl), (tv, pv)) in zip(got, PAIRS, strict=True):
            assert li == nearest(btf.light_dirs, tl, pl) and vi == nearest(btf.view_dirs, tv, pv)
    fig = gallery_figure([a, b])
    assert len(fig.axes) == 2 * len(PAIRS)
    row2 = fig.axes[len(PAIRS) :]
    assert "ramp.btf" in row2[0].get_ylabel() and "4x4 texels, 8 x 8 dirs" in row2[0].get_ylabel()
    assert [ax.get_title() for ax in row2] == [""] * len(PAIRS)  # pair names on the top row
    assert fig.axes[0].get_title().startswith("head-on\n(asked wi=0 wo=0)")
    li, vi = pair_slices(b)[2]  # the panel shows that slice, tiled 2x2, tonemapped
    shown = row2[2].get_images()[0].get_array()
    tile = np.tile(b.slice(li, vi), (2, 2, 1))
    ex = float(row2[2].get_xlabel().rsplit(" x", 1)[1])
    np.testing.assert_allclose(shown, tonemap(tile, ex), atol=2e-3 * max(1.0, ex))
    plt.close(fig)

    png = tmp_path / "gallery.png"
    r = vrn_inproc("btf", "show", str(small_btf), str(other), "-o", str(png))
    assert r.returncode == 0, r.stderr
    img = iio.imread(png)
    assert img.shape[1] > img.shape[0] and img.std() > 5
    _one_line_error(vrn_inproc("btf", "show", str(small_btf), str(other), "-o", str(png)), "exists")
    _one_line_error(
        vrn_inproc(
            "btf",
            "show",
            str(small_btf),
            str(other),
            "-o",
            str(png),
            "--force",
            "--texel",
            "1",
            "1",
        ),
        "--texel 1 1",
        "gallery of 2 files",
    )
    # every input is read before the output is touched: a missing second file names it
    before = png.read_bytes()
    _one_line_error(
        vrn_inproc(
            "btf", "show", str(small_btf), str(tmp_path / "no.btf"), "-o", str(png), "--force"
        ),
        "no.btf",
    )
    assert png.read_bytes() == before


def _one_line_error(r, *needles):
    assert r.returncode == 2, (r.returncode, r.stderr)
    err = r.stderr.strip()
    assert err.count("\n") == 0 and "Traceback" not in err, err
    for n in needles:
        assert n in err, err


class _Result:
    def __init__(self, returncode, stderr):
        self.returncode, self.stderr = returncode, stderr


@pytest.fixture
def vrn_inproc(capsys):
    """Run `vrneural ...` in this process (fast); same error path as the real entry point."""

    def run(*args):
        capsys.readouterr()
        rc = main(list(args))
        return _Result(rc, capsys.readouterr().err)

    return run


def _snapshot(p):
    return p.read_bytes(), p.stat().st_mtime_ns


def test_errors_in_a_real_process(small_btf, tmp_path):
    existing = tmp_path / "exists.btf"
    existing.write_bytes(b"precious")
    _one_line_error(
        _vrn("btf", "synth", "--preset", "velvet", "-o", str(existing), "--force"),
        "--preset",
        "velvet",
        "leather",
    )
    _one_line_error(_vrn("btf", "info", str(tmp_path / "missing.btf")), "no such file")
    assert existing.read_bytes() == b"precious"


def test_bad_inputs_are_one_line_errors_and_touch_nothing(small_btf, tmp_path, vrn_inproc):
    vrn = vrn_inproc
    existing = tmp_path / "exists.btf"
    existing.write_bytes(b"precious")
    before = _snapshot(existing)
    synth = ["btf", "synth", "--res", "4", "--dirs", "3", "--no-progress"]
    _one_line_error(
        vrn(*synth, "--preset", "velvet", "-o", str(existing), "--force"),
        "--preset",
        "velvet",
        "leather",
    )
    _one_line_error(vrn(*synth[:2], "--res", "0", "-o", str(existing), "--force"), "--res", "0")
    _one_line_error(vrn(*synth[:2], "--res", "-3", "-o", str(existing), "--force"), "--res")
    _one_line_error(vrn(*synth, "--dirs", "0", "-o", str(existing), "--force"), "--dirs")
    _one_line_error(vrn(*synth, "--dirs", "1", "-o", str(existing), "--force"), "--dirs")
    _one_line_error(
        vrn(*synth[:2], "--res", "5", "-o", str(existing), "--force"), "--res = 5", "even"
    )
    _one_line_error(vrn(*synth, "-o", str(existing)), "exists", "--force")
    _one_line_error(vrn(*synth, "-o", str(existing), "--resume"), "exists", "--force")
    assert _snapshot(existing) == before
    assert not (tmp_path / "exists.btf.partial").exists()

    out_png = tmp_path / "sheet.png"
    out_png.write_bytes(b"old png")
    png_before = _snapshot(out_png)
    _one_line_error(vrn("btf", "info", str(tmp_path / "missing.btf")), "no such file")
    _one_line_error(
        vrn("btf", "show", str(tmp_path / "missing.btf"), "-o", str(out_png), "--force"),
        "no such file",
    )
    _one_line_error(vrn("btf", "show", str(small_btf), "-o", str(out_png)), "exists")
    _one_line_error(
        vrn("btf", "show", str(small_btf), "-o", str(out_png), "--force", "--texel", "8", "0"),
        "--texel X",
    )
    wrong = tmp_path / "wrong.btf"
    wrong.write_bytes(b"VRNM\0\0\0\0" + small_btf.read_bytes()[8:])
    _one_line_error(vrn("btf", "info", str(wrong)), "is a runtime pack, expected a BTF")
    _one_line_error(
        vrn("btf", "show", str(wrong), "-o", str(out_png), "--force"),
        "is a runtime pack, expected a BTF",
    )
    trunc = tmp_path / "trunc.btf"
    trunc.write_bytes(small_btf.read_bytes()[:-100])
    _one_line_error(vrn("btf", "info", str(trunc)), "truncated")
    _one_line_error(vrn("btf", "show", str(trunc), "-o", str(out_png), "--force"), "truncated")
    assert _snapshot(out_png) == png_before
    _one_line_error(
        vrn("btf", "import", str(tmp_path / "missing_ubo.btf"), "-o", str(tmp_path / "x.btf")),
        "no such file",
    )
    _one_line_error(
        vrn("btf", "import", str(small_btf), "-o", str(existing), "--force"), "not a UBO2014"
    )
    assert _snapshot(existing) == before
    assert not (tmp_path / "x.btf").exists()


def test_synth_existing_output_with_force_is_replaced(small_btf, tmp_path):
    out = tmp_path / "f.btf"
    out.write_bytes(b"old")
    r = _vrn(
        "btf",
        "synth",
        "--preset",
        "metal",
        "--res",
        "4",
        "--dirs",
        "3",
        "-o",
        str(out),
        "--force",
        "--no-progress",
    )
    assert r.returncode == 0, r.stderr
    assert read_btf(out).meta["name"] == "metal"


def test_interrupted_partial_is_never_discarded_silently(tmp_path, vrn_inproc):
    out = tmp_path / "p.btf"
    partial = tmp_path / "p.btf.partial"
    partial.write_bytes(b"hours of work")
    synth = ["btf", "synth", "--preset", "wood", "--res", "4", "--dirs", "3", "--no-progress"]
    _one_line_error(vrn_inproc(*synth, "-o", str(out)), "--resume", "--force")
    assert partial.read_bytes() == b"hours of work" and not out.exists()
    # not a partial BTF: --resume cannot continue it and does not discard it either
    _one_line_error(vrn_inproc(*synth, "-o", str(out), "--resume"), str(partial), "--force")
    assert partial.read_bytes() == b"hours of work" and not out.exists()
    # --resume with --force contradict: an error, the partial stays
    _one_line_error(vrn_inproc(*synth, "-o", str(out), "--resume", "--force"), "contradict")
    assert partial.read_bytes() == b"hours of work" and not out.exists()
    r = vrn_inproc(*synth, "-o", str(out), "--force")  # asked for: starts over
    assert r.returncode == 0, r.stderr
    assert read_btf(out).shape == (3, 3, 4, 4) and not partial.exists()


def test_resume_with_nothing_to_resume_is_an_error_not_a_silent_fresh_start(tmp_path, vrn_inproc):
    out = tmp_path / "n.btf"
    synth = ["btf", "synth", "--preset", "wood", "--res", "4", "--dirs", "3", "--no-progress"]
    r = vrn_inproc(*synth, "-o", str(out), "--resume")
    _one_line_error(r, "vrneural btf synth: error", "nothing to resume", "n.btf.partial")
    assert not out.exists() and not (tmp_path / "n.btf.partial").exists()


def test_resume_on_a_finished_btf_says_it_is_complete_and_keeps_it(tmp_path, vrn_inproc):
    out = tmp_path / "done.btf"
    synth = ["btf", "synth", "--preset", "wood", "--res", "4", "--dirs", "3", "--no-progress"]
    assert vrn_inproc(*synth, "-o", str(out)).returncode == 0
    before = out.read_bytes()
    r = vrn_inproc(*synth, "-o", str(out), "--resume")
    _one_line_error(r, "already complete", "nothing to resume", "--force instead of --resume")
    assert out.read_bytes() == before and not (tmp_path / "done.btf.partial").exists()
    # an image import onto a finished output: the same answer, before reading anything
    r = vrn_inproc("btf", "import", str(tmp_path), "-o", str(out), "--resume", "--no-progress")
    _one_line_error(r, "already complete", "nothing to resume")
    assert out.read_bytes() == before


def test_synth_refuses_a_file_larger_than_the_free_disk_space(tmp_path, vrn_inproc, monkeypatch):
    import shutil
    from collections import namedtuple

    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda p: usage(10**9, 0, 10**6))
    out = tmp_path / "huge.btf"
    r = vrn_inproc("btf", "synth", "--res", "4", "--dirs", "300", "-o", str(out), "--no-progress")
    _one_line_error(r, "needs 8.7 MB", "only 1.0 MB is free")
    assert list(tmp_path.iterdir()) == []


def test_an_interrupted_partial_file_is_refused_by_readers(tmp_path, vrn_inproc):
    import shutil

    from vrneural.btf import BtfWriter, direction_set
    from vrneural.errors import VrnError

    d = direction_set(3)
    w = BtfWriter(tmp_path / "p.btf", d, d, (4, 4), {"name": "p"})
    w.values[:] = 0.25
    w.mark_done(0)
    copied = tmp_path / "copied.btf"
    shutil.copy(w.partial, copied)  # a .partial renamed by hand: the header says so
    for f in (copied, w.partial):
        _one_line_error(vrn_inproc("btf", "info", str(f)), str(f), "unfinished BTF file")
    with pytest.raises(VrnError, match="unfinished"):
        read_btf(copied)
    assert read_btf(w.finalize()).meta["name"] == "p"  # finished: the mark is gone


def test_header_keeps_the_configured_grid_and_its_hash(small_btf):
    """The header's SHA-256 is the BTF's identity in every checkpoint trained on it: the same
    settings must keep writing the same header bytes, or `bench quality --resume` and
    `distill` stop matching the teachers of older runs (recording the resolved grid in the
    header once did exactly that). The sidecar records the size used. (Changed once, on
    purpose: since issue #44 the file carries the tile's height field.)"""
    gen = read_btf(small_btf).meta["generator"]
    cfg = json.loads(small_btf.with_name("leather.btf.config.json").read_text())
    assert gen["grid"] == 0 and cfg["grid"] == 64
    fp = btf_fingerprint(read_btf(small_btf))
    assert fp["sha256"] == "0d0790a4551cfed27644b42ad0ed25a4dde439277ac8e2d2b254622780b820f0"


def test_grid_help_matches_the_check(vrn_inproc, tmp_path, capsys):
    from vrneural.cli import build_parser

    synth = build_parser().subcommands["btf"][0].subcommands["synth"][0]
    grid = next(a for a in synth.arguments if a.dest == "grid")
    assert "8 to 4096" in grid.help
    args = ["btf", "synth", "--res", "4", "--dirs", "3", "-o", str(tmp_path / "g.btf")]
    _one_line_error(vrn_inproc(*args, "--grid", "7"), "--grid = 7", "allowed 0 (auto) or [8, 4096]")


def test_help_shows_defaults(capsys):
    for argv, needle in (
        (["teach", "--help"], "(default: off)"),
        (["distill", "--help"], "(default: off)"),
        (["bench", "quality", "--help"], "(default: bench-quality)"),
    ):
        with pytest.raises(SystemExit):
            main(argv)
        assert needle in " ".join(capsys.readouterr().out.split()), argv


def test_help_names_every_preset(capsys):
    """`btf synth` and `btf render` list their presets from the configs' tuples, so a new
    preset (berber was missing from render's help) cannot be left out."""
    from vrneural.btf.config import PRESET_NAMES, PT_PRESET_NAMES
    from vrneural.btf.pt_presets import PT_PRESETS

    assert tuple(PT_PRESETS) == PT_PRESET_NAMES
    for argv, names in ((["btf", "synth"], PRESET_NAMES), (["btf", "render"], PT_PRESET_NAMES)):
        with pytest.raises(SystemExit):
            main([*argv, "--help"])
        text = " ".join(capsys.readouterr().out.split())
        assert f"Presets: {', '.join(names)}" in text or f"presets: {', '.join(names)}" in text
        if argv[1] == "render":  # the positional argument's help too
            assert f"render ({', '.join(names)})" in text, text


def test_unknown_argument_names_the_subcommand(capsys):
    with pytest.raises(SystemExit) as e:
        main(["export", "a.pt", "-o", "b.vrnm", "--no-progress"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1 and "usage" not in err
    assert err.startswith("vrneural export: error: unrecognized arguments: --no-progress")
    assert err.rstrip().endswith("(see 'vrneural export --help')")


def test_bad_choice_is_one_line(capsys):
    with pytest.raises(SystemExit) as e:
        main(["run", "--mode", "foo"])
    err = capsys.readouterr().err
    assert e.value.code == 2 and err.count("\n") == 1
    assert err.startswith("vrneural run: error: argument --mode: invalid choice: 'foo'")


def test_info_into_a_closed_pipe_is_quiet(small_btf):
    r = subprocess.run(
        f"{sys.executable} -m vrneural btf info {small_btf} --json | true",
        shell=True,
        capture_output=True,
        text=True,
        timeout=120,
    )
    assert "Traceback" not in r.stderr and "BrokenPipe" not in r.stderr, r.stderr


def test_info_warns_about_nan_values(tmp_path, capsys):
    from vrneural.btf import direction_set
    from vrneural.btf.sheet import BtfWarning
    from vrneural.formats.container import write_container

    d = direction_set(3)
    v = np.full((3, 3, 4, 4, 3), 0.5, np.float16)
    v[1, 2, 0, 0, 0] = np.nan
    f = tmp_path / "nan.btf"
    write_container(f, b"VRNBTF", 1, {"name": "n"}, {"values": v, "light_dirs": d, "view_dirs": d})
    with pytest.warns(BtfWarning, match="1 NaN/Inf values"):
        assert main(["btf", "info", str(f)]) == 0
    assert "max 0.5" in capsys.readouterr().out


def _interrupted_partial(out, monkeypatch, after=2):
    """Leave ``<out>.partial`` (leather, 4^2, 5 dirs) as Ctrl-C after ``after`` views does."""
    import vrneural.btf.render as render
    from vrneural.btf.synth import BtfConfig, synthesize

    real, calls = render.render_view, {"n": 0}

    def interrupt(*a, **k):
        calls["n"] += 1
        if calls["n"] > after:
            raise KeyboardInterrupt
        return real(*a, **k)

    monkeypatch.setattr(render, "render_view", interrupt)
    with pytest.raises(KeyboardInterrupt):
        synthesize(BtfConfig(preset="leather", res=4, dirs=5), out, progress=False)
    monkeypatch.setattr(render, "render_view", real)
    return out.with_name(out.name + ".partial.done")


def test_resume_with_a_damaged_list_of_finished_views_is_one_line(
    tmp_path, vrn_inproc, monkeypatch
):
    """The trial's reproduction: a stray line in `<out>.partial.done` was a traceback
    (ValueError), and an index beyond the views was counted in "resuming, k/N"."""
    out = tmp_path / "p.btf"
    done = _interrupted_partial(out, monkeypatch)
    assert done.read_text() == "0\n1\n"
    synth = ["btf", "synth", "--preset", "leather", "--res", "4", "--dirs", "5", "--no-progress"]
    resume = [*synth, "-o", str(out), "--resume"]
    done.write_text("0\n1\nx\n")
    r = vrn_inproc(*resume)
    _one_line_error(
        r, "vrneural btf synth: error", f"{done}, line 3: 'x' is not a view index", "--force"
    )
    assert "resuming" not in r.stderr and not out.exists() and done.read_text() == "0\n1\nx\n"
    done.write_text("0\n1\n999\n")
    r = vrn_inproc(*resume)
    _one_line_error(r, f"{done}, line 3: view index 999 is out of range", "5 views (0..4)")
    assert "resuming" not in r.stderr and not out.exists()
    done.write_text("0\n1\n0\n")  # a repeat counts once
    r = vrn_inproc(*resume)
    assert r.returncode == 0 and "resuming, 2/5 views already done" in r.stderr, r.stderr
    assert read_btf(out).shape == (5, 5, 4, 4) and not done.exists()


def test_show_titles_give_the_slice_shown_not_the_angles_asked(tmp_path, vrn_inproc):
    """With 8 directions the smallest theta is 17.5 deg: "head-on" is titled with that slice's
    angles, and the two pairs that pick the same slice share one panel, said on stderr too."""
    from vrneural.btf.sheet import PAIRS, dir_angles, sheet_figure, sheet_panels

    d = direction_set(8)
    vals = np.random.default_rng(0).random((8, 8, 4, 4, 3), np.float32)
    f = write_btf(tmp_path / "s8.btf", vals, d, d, {"name": "s8"})
    b = read_btf(f)
    panels = sheet_panels(b)
    titles = [p.title() for p in panels]
    assert titles[0] == "head-on (asked wi=0 wo=0)\nnearest: wi=17.5@0 wo=17.5@0, l0 v0"
    merged = [t for t in titles if "+ " in t]
    assert merged == [
        "mirror along u (asked wi=45@0 wo=45@180)\n+ grazing view (asked wi=30@0 wo=75@180)\n"
        "nearest to both: wi=17.5@0 wo=54.3@190, l0 v4"
    ]
    assert len(panels) == len(PAIRS) - 1 == 7
    assert sorted(n for p in panels for n in p.names) == sorted(n for n, *_ in PAIRS)
    assert len({(p.light, p.view) for p in panels}) == 7  # one panel per slice
    for p in panels:  # every title's "nearest" angles are those of the slice's directions
        (tl, pl), (tv, pv) = dir_angles(d[p.light]), dir_angles(d[p.view])
        assert p.title().endswith(
            f"wi={tl:.1f}@{round(pl) % 360} wo={tv:.1f}@{round(pv) % 360}, l{p.light} v{p.view}"
        )
    fig = sheet_figure(b)
    shown = [ax.get_title() for ax in fig.axes[:-1]]
    assert [t.rsplit("  x", 1)[0] for t in shown] == titles  # the PNG's titles, plus exposure
    import matplotlib.pyplot as plt

    plt.close(fig)
    png = tmp_path / "s8.png"
    r = vrn_inproc("btf", "show", str(f), "-o", str(png))
    assert r.returncode == 0 and png.exists()
    assert r.stderr.strip() == (
        f"{f}: mirror along u and grazing view resolve to the same slice "
        "(l0 v4: wi=17.5@0 wo=54.3@190) among this BTF's 8 lights x 8 views; one panel shows "
        "it, titled with both"
    )
    # UBO2014's 151 directions: eight panels, asked == shown except where the layout has no
    # such direction (its 45 deg ring is every 20 deg in phi: no 90, no 270)
    u = direction_set(151)
    g = write_btf(tmp_path / "u.btf", np.ones((151, 151, 1, 1, 3)), u, u, {"name": "u"})
    panels = sheet_panels(read_btf(g))
    assert len(panels) == 8 and panels[0].title().endswith("nearest: wi=0 wo=0, l0 v0")
    inexact = {p.names[0]: p.shown for p in panels if f"(asked {p.shown})" not in p.title()}
    assert inexact == {"mirror along v": "wi=45@80 wo=45@260"}


def test_info_shows_light_and_view_theta_ranges(tmp_path, capsys):
    """`btf info` showed only the light theta range, also in --json (`light_theta_deg`)."""
    from vrneural.btf.dirs import spherical

    ld = spherical(np.radians([0.0, 30.0, 75.0]), np.radians([0.0, 90.0, 180.0]))
    vd = spherical(np.radians([10.0, 45.0, 60.0, 85.0]), np.radians([0.0, 45.0, 90.0, 270.0]))
    f = write_btf(tmp_path / "lv.btf", np.ones((3, 4, 2, 2, 3)), ld, vd, {"name": "lv"})
    assert main(["btf", "info", str(f)]) == 0
    out = capsys.readouterr().out
    assert "dirs      light theta 0.0..75.0 deg, view theta 10.0..85.0 deg, lights != views" in out
    assert main(["btf", "info", str(f), "--json"]) == 0
    info = json.loads(capsys.readouterr().out)
    assert info["light_theta_deg"] == pytest.approx([0.0, 75.0], abs=1e-3)
    assert info["view_theta_deg"] == pytest.approx([10.0, 85.0], abs=1e-3)
    assert info["same_light_and_view_dirs"] is False


@pytest.mark.parametrize("how", ["SIGTERM", "SIGINT, ignored by the shell that started it"])
def test_synth_stops_on_a_signal_and_resumes(tmp_path, how):
    """`kill` (SIGTERM), and Ctrl-C even where a non-interactive shell started the command in
    the background with SIGINT ignored, stop `btf synth` after a whole view, as they stop
    `teach`: exit 130, the partial file kept, --resume finishes it. The same signals went
    unanswered (SIGINT) or killed it without a word (SIGTERM, exit 143) before."""
    import signal
    import time

    out = tmp_path / "s.btf"
    argv = [sys.executable, "-m", "vrneural", "btf", "synth", "--res", 64, "--dirs", 48]
    argv = [*map(str, argv), "-o", str(out), "--no-progress"]
    ignore = how.startswith("SIGINT")
    proc = subprocess.Popen(
        argv,
        stderr=subprocess.PIPE,
        text=True,
        preexec_fn=(lambda: signal.signal(signal.SIGINT, signal.SIG_IGN)) if ignore else None,
    )
    partial = tmp_path / "s.btf.partial"
    deadline = time.monotonic() + 60
    while not partial.exists() and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.05)
    assert proc.poll() is None, "finished before it could be stopped: make it bigger"
    proc.send_signal(signal.SIGINT if ignore else signal.SIGTERM)
    _, err = proc.communicate(timeout=120)
    assert proc.returncode == 130, err
    assert "interrupted after" in err and "--resume" in err, err
    assert partial.exists() and not out.exists()
    done = subprocess.run([*argv, "--resume"], capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert read_btf(out).values.shape[:2] == (48, 48)


def test_synth_catches_signals_before_the_partial_file_appears(tmp_path, monkeypatch):
    """The signal test above waits for `<out>.partial` and then signals: the handlers must
    already be in place when that file is created. They were installed just after it, and an
    ignored SIGINT that arrived in between was lost (the run finished with exit 0)."""
    import signal

    from vrneural.btf import synth
    from vrneural.interrupt import Stop

    seen = {}

    def writer(*a, **k):
        seen.update({sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)})
        raise KeyboardInterrupt  # stop before any work

    before = {sig: signal.getsignal(sig) for sig in (signal.SIGINT, signal.SIGTERM)}
    monkeypatch.setattr(synth, "BtfWriter", writer)
    with pytest.raises(KeyboardInterrupt):
        synth.synthesize(synth.BtfConfig(preset="leather", res=4, dirs=5), tmp_path / "s.btf")
    assert seen and all(getattr(h, "__func__", None) is Stop._handle for h in seen.values())
    assert before == {sig: signal.getsignal(sig) for sig in before}  # and restored after


def test_show_brdf_panel_ticks_are_whole_indices(tmp_path):
    """The unfolded BRDF's axes are light and view indices: with 20 directions matplotlib's
    default ticks were 2.5, 7.5, ..."""
    import matplotlib.pyplot as plt

    from vrneural.btf.sheet import sheet_figure

    d = direction_set(20)
    vals = np.random.default_rng(0).random((20, 20, 4, 4, 3), np.float32)
    fig = sheet_figure(read_btf(write_btf(tmp_path / "s.btf", vals, d, d, {"name": "s"})))
    fig.canvas.draw()
    for ticks in (fig.axes[-1].get_xticks(), fig.axes[-1].get_yticks()):
        assert len(ticks) and all(float(t).is_integer() for t in ticks), ticks
    plt.close(fig)


def test_synth_writes_the_tiles_height_field(small_btf, tmp_path):
    """The height field the slices were rendered from travels with them (issue #44): the
    preset's grid where it nests in the texels, else its bilinear surface resampled to the
    nearest multiple of them; ``distill --parallax auto`` reads it (docs/parallax.md)."""
    from vrneural.btf.heightfield import bilinear_wrap, texel_height
    from vrneural.btf.synth import BtfConfig, build_maps
    from vrneural.parallax import height_at_texels

    b = read_btf(small_btf)
    maps = build_maps(BtfConfig(preset="leather", res=8, dirs=6, seed=0))
    np.testing.assert_array_equal(b.height, maps.height.astype(np.float32))  # 64 = 8 x 8
    assert height_at_texels(b.height, b.resolution).shape == (8, 8)
    h = maps.height.astype(np.float32)  # [64, 64] onto 24 texels: 72 = 3 x 24 cells
    r = texel_height(h, 24)
    c = (np.arange(72) + 0.5) / 72
    assert r.shape == (72, 72)
    np.testing.assert_allclose(r[5, 7], bilinear_wrap(h, np.array(c[7]), np.array(c[5])), atol=1e-7)
    assert abs(float(r.mean()) - float(h.mean())) < 1e-4
