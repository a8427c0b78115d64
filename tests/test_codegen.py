"""Code generation in Python (gpu/unroll.py, runtime/codegen_mlp.py, codegen_sample.py): the
unrolled lines, their multiply-adds against the networks', the samplers' loads, and one golden
WGSL snapshot.

Regenerate the snapshot on purpose (after a deliberate change to the generated code, with the
frame references still passing): ``VRNEURAL_UPDATE_GOLDEN=1 pytest tests/test_codegen.py``.
"""

import itertools
import os
import re
from pathlib import Path

import numpy as np
import pytest
from runtime_helpers import count_macs

from vrneural.gpu.mlp_kernel import mlp_wgsl
from vrneural.gpu.unroll import affine_lines, mlp_lines
from vrneural.material import NeuralMaterial, random_material
from vrneural.mlp import Layer, macs, random_mlp
from vrneural.runtime.codegen import material_spec, texture_space_wgsl
from vrneural.runtime.codegen_mlp import network_wgsl

GOLDEN = Path(__file__).parent / "golden"


def _sparse(mat: NeuralMaterial, cut: float = 0.3) -> NeuralMaterial:
    """``mat`` with its small weights set to zero and a leaky first layer."""
    nets = {
        k: [
            Layer(np.where(np.abs(lay.weight) < cut, 0, lay.weight).astype(np.float32), lay.bias,
                  "leaky_relu" if i == 0 else lay.act)
            for i, lay in enumerate(v)
        ]
        for k, v in mat.networks.items()
    }  # fmt: skip
    return NeuralMaterial(mat.arch, nets, mat.textures, mat.output, mat.meta)


def test_unrolled_layers_name_every_unit_and_skip_zero_weights():
    w = np.float32([[0.5, 0.0], [-1.0, 2.0]])
    lay = [Layer(w, np.float32([0.25, 0.0]), "leaky_relu"), Layer(w[:1], np.float32([1]), "none")]
    assert mlp_lines("x", ["a", "b"], lay, "f32") == [
        "    let x1_0_p = 0.25f + 0.5f * a;",
        "    let x1_0 = max(x1_0_p, f32(0.01) * x1_0_p);",
        "    let x1_1_p = 0.0f + -1.0f * a + 2.0f * b;",
        "    let x1_1 = max(x1_1_p, f32(0.01) * x1_1_p);",
        "    let x2_0 = 1.0f + 0.5f * x1_0;",
    ]
    # hoisting: the first layer takes only column 1, on top of the named loop-invariant part
    assert mlp_lines("x", {1: "b"}, lay[:1], "f16", ["p0", "p1"], [1])[2:] == [
        "    let x1_1_p = p1 + 2.0h * b;",
        "    let x1_1 = max(x1_1_p, f16(0.01) * x1_1_p);",
    ]
    assert affine_lines("q", {0: "a"}, lay[0], [0], "f32", False) == [
        "    let q_0 = 0.5f * a;",
        "    let q_1 = -1.0f * a;",
    ]
    assert affine_lines("q", {}, lay[0], [], "f32", False)[0] == "    let q_0 = f32(0);"


@pytest.mark.parametrize("precision", ["f32", "f16"])
@pytest.mark.parametrize(
    "make",
    [
        lambda: random_material(0),
        lambda: random_material(1, width=16, channels=12, layers=3),
        lambda: random_material(2, "single", width=12, channels=6),
        lambda: _sparse(random_material(4)),
        lambda: _sparse(random_material(5, "single")),
    ],
    ids=["coarse_fine", "coarse_fine-wide", "single", "coarse_fine-sparse", "single-sparse"],
)
def test_generated_multiply_adds_equal_the_networks_macs(make, precision):
    """Every non-zero weight of every layer becomes exactly one constant multiply-add, whether
    it sits in a hoisted (per-texel) part or in the per-light part."""
    mat = make()
    T = precision
    code = network_wgsl(material_spec(mat), T)
    assert count_macs(code) == sum(macs(net) for net in mat.networks.values())
    # the per-light functions hold the first layers' direction (and latent) columns only
    fns = dict(re.findall(r"\nfn (\w+)\(.*?\n(.*?)\n\}", "\n" + code, re.S))
    first = mat.networks["mlp" if mat.arch == "single" else "coarse"][0]
    hoisted = np.count_nonzero(first.weight[:, 9:])
    if mat.arch == "single":
        assert count_macs(fns["pre_a"]) == hoisted
        assert count_macs(fns["single_net"]) == macs(mat.networks["mlp"]) - hoisted
    else:
        fine = mat.networks["fine"]
        z = mat.networks["coarse"][-1].n_out
        assert count_macs(fns["pre_a"]) == hoisted
        assert count_macs(fns["pre_b"]) == np.count_nonzero(fine[0].weight[:, z:])
        assert count_macs(fns["fine_z"]) == np.count_nonzero(fine[0].weight[:, :z])
        assert count_macs(fns["fine_net"]) == macs(fine[1:])
        assert count_macs(fns["eval_coarse"]) == macs(mat.networks["coarse"]) - hoisted


@pytest.mark.parametrize("sizes", [[5, 8, 8, 3], [17, 4, 4, 4, 6]])
def test_batched_evaluator_multiply_adds_equal_the_networks_macs(sizes):
    layers = random_mlp(sizes, 3)
    dense = sum(a * b for a, b in itertools.pairwise(sizes))
    assert count_macs(mlp_wgsl(layers)) == macs(layers) == dense
    assert count_macs(mlp_wgsl(layers, buffer_weights=True)) == 0  # loops over the buffer


@pytest.mark.parametrize(
    "name, make",
    [("texture_space_coarse_fine_f32.wgsl", lambda: texture_space_wgsl(
        random_material(7, width=4, channels=2, tex_res=4), "f32", 2)),
     ("texture_space_coarse_fine_f32_hardware.wgsl", lambda: texture_space_wgsl(
        random_material(7, width=4, channels=2, tex_res=4), "f32", 2, filtering="hardware"))],
)  # fmt: skip
def test_golden_wgsl(name, make):
    """The whole generated kernel for a fixed small pack, as checked in."""
    got = make()
    path = GOLDEN / name
    if os.environ.get("VRNEURAL_UPDATE_GOLDEN"):
        path.parent.mkdir(exist_ok=True)
        path.write_text(got)
    want = path.read_text()
    assert got == want, f"{name} changed; see this module's docstring to regenerate it"


@pytest.mark.parametrize("channels", [1, 2, 8, 12, 17])
def test_sampler_loads_each_layer_once_and_writes_each_channel_once(channels):
    from vrneural.runtime.codegen_sample import sampler_fn

    code = "\n".join(sampler_fn("s", "tex", channels))
    assert code.count("textureLoad(") == 4 * -(-channels // 8)  # 4 taps per 8-channel layer
    writes = re.findall(r"out\[(\d+)\] = ", code)
    assert sorted(map(int, writes)) == list(range(channels))
