"""`vrneural run` with the forward pass's attachments changed (argv[1], comma-separated) for an
A/B: ``discard`` (depth not stored after the pass), ``cclear`` (colour cleared by a compute pass,
then loaded by the render pass), ``load`` (colour loaded, never cleared: timing only)."""
import sys

import wgpu

from vrneural.runtime import forward as fw

V = set(sys.argv.pop(1).split(","))
_dev = fw.get_device


class _Dev:  # the renderer's device, its rgba16float eye targets also storage-writable
    def __init__(self, d):
        self._d = d

    def __getattr__(self, k):
        return getattr(self._d, k)

    def create_texture(self, **kw):
        if kw.get("format") == "rgba16float" and kw["usage"] & wgpu.TextureUsage.RENDER_ATTACHMENT:
            kw["usage"] |= wgpu.TextureUsage.STORAGE_BINDING
        return self._d.create_texture(**kw)


if "cclear" in V:
    fw.get_device = lambda: _Dev(_dev())
_pipe = {}


def _clear(encoder, tex):
    d = _dev()
    if "p" not in _pipe:
        m = d.create_shader_module(code="""
@group(0) @binding(0) var dst: texture_storage_2d<rgba16float, write>;
@compute @workgroup_size(8, 8) fn main(@builtin(global_invocation_id) g: vec3<u32>) {
    if (any(g.xy >= textureDimensions(dst))) { return; }
    textureStore(dst, g.xy, vec4<f32>(0.0));
}""")
        _pipe["p"] = d.create_compute_pipeline(layout="auto", compute={"module": m, "entry_point": "main"})
    p = _pipe["p"]
    key = id(tex)
    if key not in _pipe:
        _pipe[key] = d.create_bind_group(layout=p.get_bind_group_layout(0),
                                         entries=[{"binding": 0, "resource": tex.create_view()}])
    cp = encoder.begin_compute_pass()
    cp.set_pipeline(p)
    cp.set_bind_group(0, _pipe[key])
    cp.dispatch_workgroups((tex.width + 7) // 8, (tex.height + 7) // 8)
    cp.end()


def begin_pass(encoder, eye, timestamp_writes=None):
    if "cclear" in V:
        _clear(encoder, eye.colour)
    load = "load" if V & {"cclear", "load"} else "clear"
    att = [{"view": eye.colour_view, "load_op": load, "store_op": "store", "clear_value": (0, 0, 0, 0)}]
    if eye.vis is not None:
        att.append({"view": eye.vis_view, "load_op": "clear", "store_op": "store", "clear_value": (0, 0, 0, 0)})
    return encoder.begin_render_pass(
        color_attachments=att,
        depth_stencil_attachment={"view": eye.depth_view, "depth_load_op": "clear",
                                  "depth_store_op": "discard" if "discard" in V else "store",
                                  "depth_clear_value": 1.0},
        timestamp_writes=timestamp_writes)


fw.begin_pass = begin_pass
from vrneural.cli import main  # noqa: E402

sys.exit(main(sys.argv[1:]))
