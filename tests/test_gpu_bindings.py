"""The GPU interface declared once (gpu/bindings.py, runtime/interface.py): WGSL struct layouts
against the WGSL rules and against wgpu/naga, bind groups against the shaders that use them."""

import numpy as np
import pytest

from vrneural.gpu.bindings import ArrayOf, Binding, Bindings, Struct, layout_of
from vrneural.material import random_material
from vrneural.runtime import interface
from vrneural.runtime.codegen import material_spec

#: a struct that exercises the alignment rules: a scalar packed after a vec3, matrix columns
#: padded to 16 bytes, an array of vec3 with 16-byte strides, a nested struct
INNER = Struct("Inner", [("a", "vec2<f32>"), ("b", "u32")])
TRICKY = Struct(
    "Tricky",
    [("s", "f32"), ("v3", "vec3<f32>"), ("t", "f32"), ("m3", "mat3x3<f32>"), ("v2", "vec2<f32>"),
     ("arr", "array<vec3<f32>, 2>"), ("inner", INNER), ("u", "vec4<u32>"), ("i", "i32")],
)  # fmt: skip


def test_struct_layout_follows_the_wgsl_rules():
    # hand-computed from the WGSL spec's alignment and size rules (uniform address space)
    assert {name: f[1] for name, f in TRICKY.dtype.fields.items()} == {
        "s": 0, "v3": 16, "t": 28, "m3": 32, "v2": 80, "arr": 96, "inner": 128, "u": 144, "i": 160
    }  # fmt: skip
    assert (INNER.size, TRICKY.size) == (16, 176)
    assert TRICKY.dtype.itemsize == TRICKY.size
    assert (layout_of("mat2x2<f32>").size, layout_of("mat4x3<f32>").size) == (16, 64)
    assert layout_of("array<vec4<f32>, 3>").size == 48
    assert layout_of(ArrayOf(interface.LIGHT, 3)).size == 96
    # the passes' uniforms (the texture pass's was 176 bytes, as the shaders had written it by
    # hand, until its lod field)
    sizes = {s.name + str(s.size) for s in (interface.TEXTURE_PARAMS, interface.SCREEN_PARAMS)}
    assert sizes == {"Params192", "Params256"}
    assert (interface.LIGHT.size, interface.FRAME.size, interface.OBJECT.size) == (32, 96, 160)
    assert "    v3: vec3<f32>," in TRICKY.wgsl()
    with pytest.raises(ValueError, match="no host layout"):
        layout_of("array<f32, 4>x")


def test_bindings_refuse_a_slot_twice_and_name_missing_resources():
    with pytest.raises(ValueError, match="slot or name twice"):
        Bindings([Binding(0, "a", "storage", "array<u32>"), Binding(0, "b", "storage", "u32")])
    b = Bindings([Binding(3, "a", "storage", "array<u32>"), Binding(1, "b", "uniform", "f32")])
    assert b.wgsl() == (
        "@group(0) @binding(3) var<storage, read> a: array<u32>;\n"
        "@group(0) @binding(1) var<uniform> b: f32;"
    )
    assert b.entries({"b": 5, "a": 6}) == [
        {"binding": 3, "resource": 6},
        {"binding": 1, "resource": 5},
    ]
    with pytest.raises(KeyError, match="no binding named"):
        b.entries({"c": 1})
    # a uniform bound at dynamic offsets (the viewer's present pass: one buffer, many draws)
    dyn = Binding(0, "D", "uniform", INNER, dynamic=True).layout_entry(2, sized=True)
    assert dyn["buffer"] == {"type": "uniform", "min_binding_size": 16, "has_dynamic_offset": True}


def _copy_shader() -> tuple[str, Bindings]:
    """A kernel that copies every scalar of a TRICKY uniform into a storage array."""
    binds = Bindings([Binding(0, "U", "uniform", TRICKY),
                      Binding(1, "out", "storage_rw", "array<f32>")])  # fmt: skip
    reads = ["U.s", *(f"U.v3[{k}]" for k in range(3)), "U.t",
             *(f"U.m3[{c}][{r}]" for c in range(3) for r in range(3)), "U.v2.x", "U.v2.y",
             *(f"U.arr[{i}][{k}]" for i in range(2) for k in range(3)),
             "U.inner.a.x", "U.inner.a.y", "f32(U.inner.b)",
             *(f"f32(U.u[{k}])" for k in range(4)), "f32(U.i)"]  # fmt: skip
    body = "\n".join(f"    out[{i}] = {r};" for i, r in enumerate(reads))
    code = "\n".join([INNER.wgsl(), TRICKY.wgsl(), binds.wgsl(),
                      "@compute @workgroup_size(1)", "fn main() {", body, "}"])  # fmt: skip
    return code, binds


@pytest.mark.gpu
def test_struct_host_layout_round_trips_through_the_gpu():
    """Values written by field name on the host are the values the shader reads by field
    name, and wgpu (naga) takes the host size as the struct's binding size."""
    import wgpu

    from vrneural.gpu.device import get_device
    from vrneural.gpu.readback import read_buffer, upload_buffer

    dev = get_device()
    code, binds = _copy_shader()
    rec = TRICKY.zeros()
    want = np.arange(1, 33, dtype=np.float32)
    rec["s"], rec["v3"], rec["t"] = want[0], want[1:4], want[4]
    rec["m3"][:, :3] = want[5:14].reshape(3, 3)  # [column, row]
    rec["v2"], rec["arr"][:, :3] = want[14:16], want[16:22].reshape(2, 3)
    rec["inner"]["a"], rec["inner"]["b"] = want[22:24], 25
    rec["u"], rec["i"] = np.arange(26, 30), -7
    want[24:30] = (25, 26, 27, 28, 29, -7)
    layout = dev.create_bind_group_layout(
        entries=binds.layout_entries(wgpu.ShaderStage.COMPUTE, sized=True)
    )
    pipe = dev.create_compute_pipeline(
        layout=dev.create_pipeline_layout(bind_group_layouts=[layout]),
        compute={"module": dev.create_shader_module(code=code), "entry_point": "main"},
    )
    ubuf = upload_buffer(np.frombuffer(rec.tobytes(), np.uint8), wgpu.BufferUsage.UNIFORM)
    obuf = upload_buffer(
        np.zeros(30, np.float32), wgpu.BufferUsage.STORAGE | wgpu.BufferUsage.COPY_SRC
    )
    bg = dev.create_bind_group(
        layout=layout, entries=binds.entries({"U": {"buffer": ubuf}, "out": {"buffer": obuf}})
    )
    enc = dev.create_command_encoder()
    cp = enc.begin_compute_pass()
    cp.set_pipeline(pipe)
    cp.set_bind_group(0, bg)
    cp.dispatch_workgroups(1)
    cp.end()
    dev.queue.submit([enc.finish()])
    np.testing.assert_array_equal(read_buffer(obuf, np.float32, 30), want[:30])
    # naga's size of the struct is the host's: 4 bytes less is refused, naming it
    entries = binds.layout_entries(wgpu.ShaderStage.COMPUTE, sized=True)
    entries[0]["buffer"]["min_binding_size"] = TRICKY.size - 4
    small = dev.create_bind_group_layout(entries=entries)
    with pytest.raises(Exception, match=f"structure size {TRICKY.size}"):
        dev.create_compute_pipeline(
            layout=dev.create_pipeline_layout(bind_group_layouts=[small]),
            compute={"module": dev.create_shader_module(code=code), "entry_point": "main"},
        )


@pytest.mark.gpu
@pytest.mark.parametrize(
    "arch, weights", [("coarse_fine", "constants"), ("single", "uniform"), ("single", "storage")]
)
@pytest.mark.parametrize("mode", ["texture", "screen"])
def test_pass_interfaces_declare_what_their_shaders_use(arch, weights, mode):
    """Explicit layouts made from the Python tables (kinds, types, uniform sizes) are accepted
    by wgpu for every entry point of the generated kernels."""
    import wgpu

    from vrneural.gpu.device import get_device
    from vrneural.runtime.codegen import screen_space_wgsl, texture_space_wgsl

    mat = random_material(3, arch)
    spec = material_spec(mat, weights)
    if mode == "texture":
        code, binds = (
            texture_space_wgsl(mat, "f32", 2, weights),
            interface.texture_bindings(spec, 2),
        )
        entries = ("main", "cull", "args", "main_compacted", "bare")
    else:
        code, binds = screen_space_wgsl(mat, "f32", 2, weights), interface.screen_bindings(spec, 2)
        entries = ("main", "cull", "args")
    dev = get_device()
    layout = dev.create_bind_group_layout(
        entries=binds.layout_entries(wgpu.ShaderStage.COMPUTE, sized=True)
    )
    mod = dev.create_shader_module(code=code)
    for e in entries:
        dev.create_compute_pipeline(
            layout=dev.create_pipeline_layout(bind_group_layouts=[layout]),
            compute={"module": mod, "entry_point": e},
        )
