"""What `vrneural`'s start-up loads: the parser needs each command's config dataclass and light
modules (no numpy), never a stage's run-time code; each handler imports its stage when the
command runs (vrneural/cli/__init__.py)."""

import dataclasses
import json
import subprocess
import sys

#: loaded by no parser: heavy libraries, process pools, and the stages' run-time modules
RUN_TIME = (
    "numpy",
    "multiprocessing",
    "concurrent.futures.process",
    "tomllib",
    "torch",
    "wgpu",
    "mitsuba",
    "scipy",
    "jinja2",
    "matplotlib",
    "imageio",
    "trimesh",
    "glfw",
    "rendercanvas",
    "tqdm",
    "vrneural.atlas.build",
    "vrneural.atlas.io",
    "vrneural.bench.report",
    "vrneural.bench.quality",
    "vrneural.bench.quality_report",
    "vrneural.bench.quality_train",
    "vrneural.bench.frame",
    "vrneural.bench.frame_report",
    "vrneural.bench.packs",
    "vrneural.bench.timing",
    "vrneural.bench.trade_scene",
    "vrneural.bench.tradeoff",
    "vrneural.btf.format",
    "vrneural.btf.sheet",
    "vrneural.btf.synth",
    "vrneural.distill.teach",
    "vrneural.formats.vrnm",
    "vrneural.material",
    "vrneural.runtime.run",
    "vrneural.runtime.scene",
    "vrneural.scoring.score",
    "vrneural.viewer.view",
    "vrneural.viewer.frame",
)
#: vrneural modules build_parser() loads (38 when this was written): a new one is a choice
MAX_VRNEURAL = 38


def test_build_parser_loads_configs_not_stages():
    code = (
        "import json, sys; from vrneural.cli import build_parser; build_parser(); "
        "print(json.dumps(sorted(sys.modules)))"
    )
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    loaded = json.loads(out.stdout)
    assert [m for m in RUN_TIME if m in loaded] == []
    ours = [m for m in loaded if m.split(".")[0] == "vrneural"]
    assert len(ours) <= MAX_VRNEURAL, ours


def test_light_copies_of_choices():
    """The light config modules copy two tuples of choices rather than import numpy-heavy
    modules at start-up; the copies stay equal to the originals."""
    from vrneural.distill.config import PARALLAX
    from vrneural.parallax import PARALLAX_CHOICES, RENDER_MARCHES
    from vrneural.runtime.config import RunConfig

    assert PARALLAX == PARALLAX_CHOICES
    marches = next(f for f in dataclasses.fields(RunConfig) if f.name == "parallax_march")
    assert tuple(marches.metadata["choices"]) == RENDER_MARCHES


def test_a_command_without_torch_says_what_to_install(tmp_path):
    """PyTorch is an optional extra: a command that needs it, where it is missing, prints one
    line naming the extra and exits 2, leaving no output behind."""
    code = (
        "import sys; sys.modules['torch'] = None; from vrneural.cli import main; "
        "sys.exit(main(sys.argv[1:]))"
    )
    btf = tmp_path / "m.btf"
    btf.write_bytes(b"")  # never read: the stage's import comes first
    for argv in (["teach", str(btf), "-o", "t.pt"], ["bench", "quality", "--quick"]):
        r = subprocess.run(
            [sys.executable, "-c", code, *argv], capture_output=True, text=True, cwd=tmp_path
        )
        assert r.returncode == 2, r.stderr
        assert r.stderr.count("\n") == 1 and "pip install 'vrneural[train]'" in r.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.btf"]
