// One level of a radiance texture's mip chain from the level above it. Texels hold radiance
// premultiplied by coverage (level 0: coverage 1 where a block was shaded, 0 on empty texels,
// whose radiance is 0), so the plain 2x2 mean is the coverage-weighted mean: empty and gutter
// texels do not darken chart edges, and the forward pass divides by the filtered coverage.
// numpy twin: runtime/radiance_mips.py:mip_chain. A source texel past an odd level's last
// row or column is dropped (WebGPU's floor(R / 2^k) level sizes).
// Bindings (src, dst): runtime/radiance_mips.py:MIP_BINDINGS.
{{ bindings }}

@compute @workgroup_size(8, 8)
fn main(@builtin(global_invocation_id) gid: vec3<u32>) {
    let d = textureDimensions(dst);
    if (gid.x >= d.x || gid.y >= d.y) { return; }
    let p = vec2<i32>(gid.xy) * 2;
    let s = textureLoad(src, p, 0) + textureLoad(src, p + vec2<i32>(1, 0), 0)
          + textureLoad(src, p + vec2<i32>(0, 1), 0) + textureLoad(src, p + vec2<i32>(1, 1), 0);
    textureStore(dst, vec2<i32>(gid.xy), s * 0.25);
}
