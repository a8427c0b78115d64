"""Reports of `bench kernels`, `bench lights` and `bench materials`: the kernels' speed-up column
with any subset of precisions, the roofline flag, plot layout (from made-up records, no adapter)
and tiny end-to-end runs (a few seconds each on lavapipe)."""

import json
import re

import pytest

from vrneural.bench import kernels, lights
from vrneural.bench import report as rp
from vrneural.cli import main


def _rec(network, variant, precision, ms, gflops=1.0):
    return {
        "network": network,
        "variant": variant,
        "precision": precision,
        "texels": 1024,
        "macs_per_texel": 218,
        "ms": ms,
        "texels_per_s": 1024 / ms * 1e3,
        "gflops": gflops,
        "fraction_of_sgemm": gflops / 10.0,
    }


def _doc(records, is_cpu=True, runs=(10.0, 9.0)):
    return {
        "adapter": {"name": "fake", "backend": "Vulkan", "is_cpu": is_cpu},
        "config": {"texels": 1024, "repeats": 1, "sgemm_n": 64, "quick": True},
        "torch_threads": 2,
        "sgemm_gflops_runs": list(runs),
        "sgemm_gflops": max(runs),
        "records": records,
    }


def test_kernels_speedups_with_f16_only_compare_with_f16_constants():
    doc = _doc([_rec("student", "constants", "f16", 2.0), _rec("student", "torch", "f32", 4.0)])
    assert kernels.add_speedups(doc) == "f16" and doc["speedup_reference"] == "constants f16"
    assert [r["speedup_vs_constants_f16"] for r in doc["records"]] == [1.0, 0.5]
    assert [r["speedup_vs_constants"] for r in doc["records"]] == [1.0, 0.5]
    md = "\n".join(kernels.markdown(doc))
    assert "| speed vs constants f16 |" in md
    assert "No f32 kernel was measured, so the reference is f16" in md


def test_kernels_speedups_prefer_f32_and_leave_a_dash_without_constants():
    doc = _doc(
        [
            _rec("student", "constants", "f16", 2.0),
            _rec("student", "constants", "f32", 1.0),
            _rec("neumip", "torch", "f32", 4.0),
        ]
    )
    assert kernels.add_speedups(doc) == "f32"
    assert [r["speedup_vs_constants_f32"] for r in doc["records"]] == [0.5, 1.0, None]
    md = kernels.markdown(doc)
    assert "| of sgemm | speed vs constants f32 |" in "\n".join(md)
    assert md[-1].startswith("speed vs constants f32: the same network's constants f32 kernel")
    assert any(
        line.startswith("| neumip | torch | f32 |") and line.endswith("| - |") for line in md
    )


def test_kernels_flag_a_kernel_measured_above_the_roofline_on_a_cpu_adapter():
    recs = [_rec("student", "constants", "f32", 1.0, gflops=25.0)]
    doc = _doc(recs, runs=(2.1, 10.0))
    kernels.add_speedups(doc)
    md = "\n".join(kernels.markdown(doc))
    assert "**Roofline unreliable:** 1 kernel(s) measured above numpy sgemm (up to 25.0" in md
    assert "numpy sgemm varied 2.1 to 10.0 GFLOP/s within this run" in md
    assert "the better of 2.1 and 10.0 measured before and after the kernels" in md
    gpu = _doc(recs, is_cpu=False, runs=(10.0, 10.0))  # a GPU beats the CPU's sgemm: no flag
    kernels.add_speedups(gpu)
    md = "\n".join(kernels.markdown(gpu))
    assert "Roofline unreliable" not in md and "varied" not in md


def _captured(monkeypatch):
    figs = []
    monkeypatch.setattr(rp, "save_png", lambda fig, path: figs.append(fig))
    return figs


def test_kernels_legend_is_outside_the_bars(monkeypatch):
    figs = _captured(monkeypatch)
    recs = [
        _rec(n, v, p, 1.0, gflops=g)
        for n, g in (("student", 3.0), ("neumip", 40.0))
        for v, p in (("constants", "f32"), ("constants", "f16"), ("buffer", "f32"))
    ]
    kernels.plot(_doc(recs), "unused.png")
    fig = figs[0]
    fig.canvas.draw()
    ax = fig.axes[0]
    legend = ax.get_legend().get_window_extent()
    assert legend.x0 >= ax.get_window_extent().x1  # right of the axes: covers no bar


def test_lights_plot_has_integer_light_ticks(monkeypatch):
    figs = _captured(monkeypatch)
    recs = [
        {"lights": k, "fps": 10.0 / k, "shading_ms_per_frame": 2.0 * k, "forward_ms": 1.0}
        for k in (1, 2, 4)
    ]
    lights.plot({"adapter": {"name": "fake"}, "records": recs}, 2.0, "unused.png")
    fig = figs[0]
    fig.canvas.draw()
    for ax in fig.axes:
        lo, hi = ax.get_xlim()
        ticks = [t for t in ax.get_xticks() if lo <= t <= hi]
        assert ticks and all(float(t).is_integer() for t in ticks), ticks


@pytest.mark.gpu
def test_bench_kernels_with_f16_alone_writes_its_report(tmp_path):
    from vrneural.gpu.device import adapter_summary

    if not adapter_summary().features.get("shader-f16"):
        pytest.skip("the adapter lacks shader-f16")
    out = tmp_path / "k"
    argv = ["bench", "kernels", "--quick", "--precisions", "f16", "--networks", "student"]
    argv += ["--texels", "1024", "--sgemm-n", "64", "--repeats", "1", "--no-progress"]
    assert main([*argv, "--out", str(out)]) == 0
    doc = json.loads((out / "results.json").read_text())
    assert {r["precision"] for r in doc["records"]} == {"f16", "f32"}  # torch is f32
    assert doc["speedup_reference"] == "constants f16" and len(doc["sgemm_gflops_runs"]) == 2
    assert all(r["speedup_vs_constants_f16"] > 0 for r in doc["records"])
    assert "| speed vs constants f16 |" in (out / "results.md").read_text()
    assert (out / "kernels.png").is_file()


@pytest.mark.gpu
@pytest.mark.parametrize("bench", ["lights", "materials"])
def test_lights_and_materials_say_fps_is_from_the_mean_frame_time(tmp_path, bench):
    out = tmp_path / bench
    argv = ["bench", bench, f"--{bench}", "1,2", "--texture-res", "128", "--eye-res", "32x32"]
    argv += ["--eyes", "1", "--reuse", "0", "--warmup", "0", "--no-progress", "--out", str(out)]
    assert main(argv) == 0
    md = (out / "results.md").read_text()
    assert f"| {bench} | FPS (mean frame ms) | frame ms median |" in md
    assert "FPS: 1000 / the mean frame ms (wall clock incl. GPU wait)" in md
    doc = json.loads((out / "results.json").read_text())
    for r in doc["records"]:
        assert r["fps"] == pytest.approx(1e3 / r["frame_ms"]["mean"])


def test_list_options_refuse_a_value_named_twice():
    from vrneural.bench.configs import KernelsConfig
    from vrneural.errors import VrnError

    assert KernelsConfig(precisions="f16, f32").precisions == ("f16", "f32")
    with pytest.raises(VrnError, match="--precisions names f16 more than once"):
        KernelsConfig(precisions=("f16", "f16"))


def test_kernels_time_the_networks_distill_trains():
    """MACs per texel of the README's Models table (the trained shapes: M_c 2 layers, NeuMIP
    reading wi.xy and wo.xy), and student:W as distill --width W."""
    from vrneural.errors import VrnError

    names = ("student", "single8", "neumip", "student:16", "single8:12", "single8:8",
             "student_offset", "neumip_offset")  # fmt: skip
    macs = {n: kernels.network(n)[1] for n in names}
    assert macs == {
        "student": 202,
        "single8": 288,
        "neumip": 1600,
        # + the offset MLP of its size per texel: (4 + 2) -> 8 -> 8 -> 1, (7 + 2) -> 25 x 3 -> 1
        "student_offset": 202 + 6 * 8 + 8 * 8 + 8,
        "neumip_offset": 1600 + 9 * 25 + 2 * 25 * 25 + 25,
        "student:16": 564,
        "single8:12": 17 * 12 + 2 * 12 * 12 + 12 * 3,
        "single8:8": 288,
    }
    coarse, fine = (layers for layers, _ in kernels.network("student:4")[0])
    assert [(x.n_in, x.n_out) for x in coarse + fine] == [(17, 4), (4, 4), (12, 4), (4, 3)]
    names = ("student", "student:12", "neumip")
    assert kernels.KernelsConfig(networks="student, student:12,neumip").networks == names
    for bad, msg in (
        ("student:0", "student:W needs a width W in [1, 64]"),
        ("student:x", "student:W needs a width W in [1, 64]"),
        ("student:8,student:8", "--networks names student:8 more than once"),
        ("single8:65", "single8:W needs a width W in [1, 64]"),
        ("single8,single8:8", "--networks names single8 and single8:8, the same network"),
        ("resnet", "choose one of: neumip, neumip_offset, single8, single8:W, student, student:W"),
        (" , ", "--networks is empty"),
    ):
        with pytest.raises(VrnError, match=re.escape(msg)):
            kernels.KernelsConfig(networks=bad)


@pytest.mark.gpu
def test_bench_kernels_times_a_student_of_another_width(tmp_path):
    out = tmp_path / "k"
    argv = ["bench", "kernels", "--networks", "student:4,student", "--precisions", "f32"]
    argv += ["--texels", "1024", "--sgemm-n", "64", "--repeats", "1", "--no-progress"]
    assert main([*argv, "--out", str(out)]) == 0
    doc = json.loads((out / "results.json").read_text())
    got = {(r["network"], r["variant"]): r["macs_per_texel"] for r in doc["records"]}
    assert got[("student:4", "constants")] == 81 and got[("student", "torch")] == 202
    assert "| student:4 | constants | f32 | 81 |" in (out / "results.md").read_text()
