// Counting sort of points by cell, in four entry points run in order:
//   bin:        cell of each point (the bin `n_cells` collects points outside the grid) and a
//               count per bin;
//   (scan.wgsl turns the counts into bin starts)
//   scatter:    each point claims a slot in its bin (in arbitrary order);
//   order_bins: sorts each bin by the points' previous index, so the result is exactly the
//               CPU's stable counting sort whatever order the slots were claimed in.
// Points are records of STRIDE words starting with x, y, z. Only the first `limit[0]` points
// take part (the active soil; escaped particles keep their places after them).

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> points: array<f32>;
@group(0) @binding(2) var<storage, read> limit: array<u32>;
@group(0) @binding(3) var<storage, read_write> cell_of: array<u32>;
@group(0) @binding(4) var<storage, read_write> counts: array<atomic<u32>>;
@group(0) @binding(5) var<storage, read> start: array<u32>;
@group(0) @binding(6) var<storage, read_write> order: array<u32>;

@compute @workgroup_size(64)
fn bin(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= limit[0]) { return; }
    let p = vec3<f32>(points[i * STRIDE], points[i * STRIDE + 1u], points[i * STRIDE + 2u]);
    let c = cell_coords(p);
    var cell = prm.n_cells;
    if (c.x >= 0) { cell = cell_linear(u32(c.x), u32(c.y), u32(c.z)); }
    cell_of[i] = cell;
    atomicAdd(&counts[cell], 1u);
}

@compute @workgroup_size(64)
fn scatter(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= limit[0]) { return; }
    let c = cell_of[i];
    let slot = start[c] + atomicAdd(&counts[c], 1u);
    order[slot] = i;
}

@compute @workgroup_size(64)
fn order_bins(@builtin(global_invocation_id) gid: vec3<u32>) {
    let c = flat(gid);
    if (c > prm.n_cells) { return; }
    let a = start[c];
    let b = start[c + 1u];
    // Insertion sort: bins hold a handful of points.
    for (var k = a + 1u; k < b; k++) {
        let v = order[k];
        var j = k;
        while (j > a && order[j - 1u] > v) {
            order[j] = order[j - 1u];
            j--;
        }
        order[j] = v;
    }
}
