// Exclusive prefix sum of LEN bin counts into LEN + 1 starts (the last is the total), in three
// passes: each workgroup scans a block of SCAN_BLOCK (= 256 threads × PER) counts and writes its
// total; one workgroup scans the block totals (in chunks, carrying the running sum); each block
// adds its offset. Within a block each thread first sums its PER neighbouring counts serially
// and only the 256 thread totals go through the barrier-synchronised tree (issue 46: with 512
// counts a block, one per leaf, `scan_blocks` took 16 % of a step of the dry column collapse on
// lavapipe, whose barriers are costly; with 2048 the whole step is 6 % faster there).

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> counts: array<u32>;
@group(0) @binding(2) var<storage, read_write> start: array<u32>;
@group(0) @binding(3) var<storage, read_write> sums: array<u32>;

const PER: u32 = SCAN_BLOCK / 256u;
var<workgroup> tile: array<u32, SCAN_BLOCK>;
var<workgroup> part: array<u32, 256>;

// Work-efficient (Blelloch) exclusive scan of the 256 entries of `part`; returns their total.
fn scan_part(t: u32) -> u32 {
    var offset = 1u;
    for (var d = 128u; d > 0u; d >>= 1u) {
        workgroupBarrier();
        if (t < d) {
            let ai = offset * (2u * t + 1u) - 1u;
            let bi = offset * (2u * t + 2u) - 1u;
            part[bi] += part[ai];
        }
        offset <<= 1u;
    }
    workgroupBarrier();
    let total = part[255];
    workgroupBarrier();
    if (t == 0u) { part[255] = 0u; }
    for (var d = 1u; d < 256u; d <<= 1u) {
        offset >>= 1u;
        workgroupBarrier();
        if (t < d) {
            let ai = offset * (2u * t + 1u) - 1u;
            let bi = offset * (2u * t + 2u) - 1u;
            let x = part[ai];
            part[ai] = part[bi];
            part[bi] += x;
        }
    }
    workgroupBarrier();
    return total;
}

// Exclusive scan of `tile` in place (thread t owns entries t * PER .. t * PER + PER - 1);
// returns the total. The tile must be loaded, and is read after, across a barrier.
fn scan_tile(t: u32) -> u32 {
    workgroupBarrier();
    var sum = 0u;
    for (var k = 0u; k < PER; k++) {
        let x = tile[t * PER + k];
        tile[t * PER + k] = sum;
        sum += x;
    }
    part[t] = sum;
    let total = scan_part(t);
    let offset = part[t];
    for (var k = 0u; k < PER; k++) {
        tile[t * PER + k] += offset;
    }
    workgroupBarrier();
    return total;
}

@compute @workgroup_size(256)
fn scan_blocks(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let t = lid.x;
    let block = wg.x + wg.y * ROW_GROUPS;
    let base = block * SCAN_BLOCK;
    for (var k = 0u; k < PER; k++) {
        let i = base + t + k * 256u;
        var v = 0u;
        if (i < LEN) { v = counts[i]; }
        tile[t + k * 256u] = v;
    }
    let total = scan_tile(t);
    for (var k = 0u; k < PER; k++) {
        let i = base + t + k * 256u;
        if (i < LEN) { start[i] = tile[t + k * 256u]; }
    }
    if (t == 0u) { sums[block] = total; }
}

@compute @workgroup_size(256)
fn scan_sums(@builtin(local_invocation_id) lid: vec3<u32>) {
    let t = lid.x;
    var carry = 0u;
    for (var base = 0u; base < BLOCKS; base += SCAN_BLOCK) {
        for (var k = 0u; k < PER; k++) {
            let i = base + t + k * 256u;
            var v = 0u;
            if (i < BLOCKS) { v = sums[i]; }
            tile[t + k * 256u] = v;
        }
        let total = scan_tile(t);
        for (var k = 0u; k < PER; k++) {
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
    if (i < LEN) { start[i] += sums[i / SCAN_BLOCK]; }
}
