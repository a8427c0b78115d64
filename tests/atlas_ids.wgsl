// Triangle-ID rasterization in atlas-UV space (GPU twin of vrneural/atlas/raster.py:
// raster_coverage). One r32uint target of R x R texels, cleared to EMPTY (0xFFFFFFFF).
// Texel (x, y) has its centre at atlas uv ((x + 0.5) / R, (y + 0.5) / R) and row y = 0 is the
// first row in memory (framebuffer y down), so uv maps to clip space as (2u - 1, 1 - 2v): no
// v flip in texel terms. Triangles are drawn non-indexed, 3 vertices per face in face order,
// so the triangle ID is vertex_index / 3. The rasterizer's own top-left rule decides centres
// on shared edges; where UVs overlap, the later triangle wins (the CPU keeps the lowest ID).

struct VsOut {
    @builtin(position) pos: vec4<f32>,
    @location(0) @interpolate(flat) tri: u32,
};

@vertex
fn vs_main(@builtin(vertex_index) vi: u32, @location(0) uv: vec2<f32>) -> VsOut {
    var out: VsOut;
    out.pos = vec4<f32>(2.0 * uv.x - 1.0, 1.0 - 2.0 * uv.y, 0.0, 1.0);
    out.tri = vi / 3u;
    return out;
}

@fragment
fn fs_main(in: VsOut) -> @location(0) u32 {
    return in.tri;
}
