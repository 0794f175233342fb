// Exclusive prefix sum of LEN bin counts into LEN + 1 starts (the last is the total), in three
// passes: each workgroup scans a block of 2 * 256 counts and writes its total; one workgroup
// scans the block totals (in chunks, carrying the running sum); each block adds its offset.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> counts: array<u32>;
@group(0) @binding(2) var<storage, read_write> start: array<u32>;
@group(0) @binding(3) var<storage, read_write> sums: array<u32>;

const BLOCK: u32 = 512u;
var<workgroup> tile: array<u32, 512>;

// Work-efficient (Blelloch) exclusive scan of `tile`; returns the total.
fn scan_tile(t: u32) -> u32 {
    var offset = 1u;
    for (var d = BLOCK >> 1u; d > 0u; d >>= 1u) {
        workgroupBarrier();
        if (t < d) {
            let ai = offset * (2u * t + 1u) - 1u;
            let bi = offset * (2u * t + 2u) - 1u;
            tile[bi] += tile[ai];
        }
        offset <<= 1u;
    }
    workgroupBarrier();
    let total = tile[BLOCK - 1u];
    workgroupBarrier();
    if (t == 0u) { tile[BLOCK - 1u] = 0u; }
    for (var d = 1u; d < BLOCK; d <<= 1u) {
        offset >>= 1u;
        workgroupBarrier();
        if (t < d) {
            let ai = offset * (2u * t + 1u) - 1u;
            let bi = offset * (2u * t + 2u) - 1u;
            let x = tile[ai];
            tile[ai] = tile[bi];
            tile[bi] += x;
        }
    }
    workgroupBarrier();
    return total;
}

@compute @workgroup_size(256)
fn scan_blocks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let t = lid.x;
    let block = wg.x + wg.y * ROW_GROUPS;
    let base = block * BLOCK;
    for (var k = 0u; k < 2u; k++) {
        let i = base + t + k * 256u;
        var v = 0u;
        if (i < LEN) { v = counts[i]; }
        tile[t + k * 256u] = v;
    }
    let total = scan_tile(t);
    for (var k = 0u; k < 2u; k++) {
        let i = base + t + k * 256u;
        if (i < LEN) { start[i] = tile[t + k * 256u]; }
    }
    if (t == 0u) { sums[block] = total; }
}

@compute @workgroup_size(256)
fn scan_sums(@builtin(local_invocation_id) lid: vec3<u32>) {
    let t = lid.x;
    var carry = 0u;
    for (var base = 0u; base < BLOCKS; base += BLOCK) {
        for (var k = 0u; k < 2u; k++) {
            let i = base + t + k * 256u;
            var v = 0u;
            if (i < BLOCKS) { v = sums[i]; }
            tile[t + k * 256u] = v;
        }
        let total = scan_tile(t);
        for (var k = 0u; k < 2u; k++) {
            let i = base + t + k * 256u;
            if (i < BLOCKS) { sums[i] = tile[t + k * 256u] + carry; }
        }
        carry += total;
        workgroupBarrier();
    }
    if (t == 0u) { start[LEN] = carry; }
}

@compute @workgroup_size(256)
fn add_sums(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x + gid.y * (ROW_GROUPS * 256u);
    if (i < LEN) { start[i] += sums[i / BLOCK]; }
}
