// `vrneural view`: draws the renderer's HDR eye textures into the window's (or any 8-bit)
// target. One draw per panel (an eye, or a half of the split view), each a full-screen
// triangle cut to its rectangle by the scissor: per pixel, the source pixel under it (nearest;
// exact at scale 1), tonemapped through a 65536-entry table indexed by the f16 bits of each
// channel, made by output.tonemap itself, so the window shows bit for bit what `vrneural run`
// writes to its PNGs. Then overlays (the HUD, light markers, the split line), alpha-blended.
// No branch per pixel beyond the table's gathers: llvmpipe runs both sides of every branch.
// Numpy twin: viewer/present.py:compose.

// The Draw uniform and the bindings: viewer/present.py:DRAW, PRESENT_BINDINGS.
{{ structs }}

// the target encodes sRGB: decode first (a pipeline constant: no per-pixel cost otherwise)
override SRGB: bool = false;

{{ bindings }}

@vertex
fn vs_main(@builtin(vertex_index) i: u32) -> @builtin(position) vec4<f32> {
    let uv = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    return vec4<f32>(uv * 2.0 - 1.0, 0.0, 1.0);
}

fn channel(v: f32) -> f32 {
    return f32(lut[pack2x16float(vec2<f32>(v, 0.0)) & 0xffffu]) / 255.0;
}

fn srgb_to_linear(c: vec3<f32>) -> vec3<f32> {
    let lo = c / 12.92;
    let hi = pow((c + 0.055) / 1.055, vec3<f32>(2.4));
    return select(hi, lo, c <= vec3<f32>(0.04045));
}

fn encoded(c: vec3<f32>) -> vec3<f32> {
    if (SRGB) {
        return srgb_to_linear(c);
    }
    return c;
}

fn source(pos: vec2<f32>) -> vec4<f32> {
    return textureLoad(src, vec2<i32>(floor((pos - D.origin) / D.scale)), 0);
}

// an HDR eye: tonemapped through the table
@fragment
fn fs_panel(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let v = source(pos.xy);
    return vec4<f32>(encoded(vec3<f32>(channel(v.x), channel(v.y), channel(v.z))), 1.0);
}

// display colours (the FLIP heat map): as they are
@fragment
fn fs_display(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    return vec4<f32>(encoded(source(pos.xy).rgb), 1.0);
}

@fragment
fn fs_overlay(@builtin(position) pos: vec4<f32>) -> @location(0) vec4<f32> {
    let q = vec2<i32>(floor(pos.xy - D.origin));
    let o = select(textureLoad(src, q, 0) * D.tint, D.tint, D.kind == 1u);
    return vec4<f32>(encoded(o.rgb), o.a);
}
