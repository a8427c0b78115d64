// Work compaction shared by texture_space.wgsl and screen_space.wgsl: a `cull` entry point
// appends the items worth shading (blocks, pixels; packed y << 16 | x) to `todo`, `args` turns
// their count into indirect workgroup counts (padding `todo` with EMPTY to whole workgroups and
// zeroing the count for the next use), and `main` shades todo[todo_index(...)] only
// (dispatch_workgroups_indirect). Host side: runtime/texture_pass.py (CompactionBuffers,
// dispatch_compacted). Needs a global `const EMPTY: u32 = 0xFFFFFFFFu;` and the
// `counters: array<atomic<u32>>` storage binding; its bindings (todo, todo_n, ind) are declared
// by runtime/interface.py (COMPACT).


{% macro fns(subgroups=false) %}
{% if subgroups %}
// Append `value` to todo where `keep`, with subgroup operations (device feature "subgroup"):
// the slot within the subgroup is an exclusive prefix sum of the keep flags, and one global
// atomic per subgroup reserves the subgroup's run. No workgroup barrier or workgroup atomic
// (llvmpipe runs barriers as coroutine switches); on llvmpipe the timing difference to the
// workgroup variant below stayed within the machine's noise (docs/runtime.md). Call from
// subgroup-uniform control flow.
fn compact_append(keep: bool, value: u32, lid: u32) {
    let one = select(0u, 1u, keep);
    let slot = subgroupExclusiveAdd(one);
    let total = subgroupAdd(one);
    var base = 0u;
    if (subgroupBroadcastFirst(lid) == lid && total != 0u) {  // the first active invocation
        base = atomicAdd(&todo_n[0], total);
    }
    base = subgroupBroadcastFirst(base);
    if (keep) { todo[base + slot] = value; }
}

// Add `x`, summed over the subgroup, to counters[idx] (one atomic per subgroup).
fn count_add(idx: u32, x: u32, lid: u32) {
    let t = subgroupAdd(x);
    if (subgroupBroadcastFirst(lid) == lid && t != 0u) { atomicAdd(&counters[idx], t); }
}
{% else %}
var<workgroup> wg_n: atomic<u32>;
var<workgroup> wg_base: u32;

// Append `value` to todo where `keep`: one workgroup atomic per item, one global atomic per
// workgroup. Call from uniform control flow (it holds barriers; they also complete any other
// workgroup atomics done before the call). The workgroup counter is reset explicitly, not left
// to WGSL's zero initialisation: without this reset the render tests hung on llvmpipe.
fn compact_append(keep: bool, value: u32, lid: u32) {
    if (lid == 0u) { atomicStore(&wg_n, 0u); }
    workgroupBarrier();
    var slot = 0u;
    if (keep) { slot = atomicAdd(&wg_n, 1u); }
    workgroupBarrier();
    if (lid == 0u) { wg_base = atomicAdd(&todo_n[0], atomicLoad(&wg_n)); }
    let base = workgroupUniformLoad(&wg_base);
    if (keep) { todo[base + slot] = value; }
}

var<workgroup> wg_sum: atomic<u32>;

// Add `x`, summed over the workgroup, to counters[idx] (one workgroup atomic per invocation,
// one global atomic per workgroup). `idx` must be workgroup-uniform; call from uniform control
// flow (barriers; the sum is reset explicitly, as in compact_append).
fn count_add(idx: u32, x: u32, lid: u32) {
    if (lid == 0u) { atomicStore(&wg_sum, 0u); }
    workgroupBarrier();
    if (x != 0u) { atomicAdd(&wg_sum, x); }
    workgroupBarrier();
    if (lid == 0u) {
        let t = atomicLoad(&wg_sum);
        if (t != 0u) { atomicAdd(&counters[idx], t); }
    }
}
{% endif %}

// Index of a 1D, 64-wide invocation in a grid of (x, y) workgroups (runtime.texture_pass.grid).
fn todo_index(wid: vec3<u32>, nwg: vec3<u32>, lid: u32) -> u32 {
    return (wid.y * nwg.x + wid.x) * 64u + lid;
}

@compute @workgroup_size(1)
fn args() {
    let n = atomicExchange(&todo_n[0], 0u);  // and zero for the next use
    let wg = (n + 63u) / 64u;
    let y = max(1u, (wg + 65534u) / 65535u);
    let x = (wg + y - 1u) / y;
    ind[0] = x;
    ind[1] = y;
    ind[2] = 1u;
    for (var k = n; k < x * y * 64u; k++) { todo[k] = EMPTY; }
}
{% endmacro %}
