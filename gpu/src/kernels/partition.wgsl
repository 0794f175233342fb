// The stable partition of the active region's classification (see classify.wgsl): `place`
// moves each record to its place, awake | extended | asleep | outside, each in its earlier
// order, flagged frozen unless awake; `tally` writes the count of each role and the number
// of particles the next sort takes (awake and extended). `kstart` is the exclusive scan of
// three segments of `n` keys (awake, extended, asleep), so `kstart[r n + i]` is where
// particle i goes if its role is r. CPU twin: `ActiveRegion::classify`.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> role: array<u32>;
@group(0) @binding(2) var<storage, read> kstart: array<u32>;
@group(0) @binding(3) var<storage, read> parts: array<Particle>;
@group(0) @binding(4) var<storage, read_write> dst: array<Particle>;
@group(0) @binding(5) var<storage, read_write> counts: array<u32>;
@group(0) @binding(6) var<storage, read_write> info: Info;

@compute @workgroup_size(64)
fn place(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    let n = prm.n;
    if (i >= n) { return; }
    let r = role[i];
    var k = 0u;
    if (r < 3u) {
        k = kstart[r * n + i];
    } else {
        // Outside: after the other three, in order among the outside ones.
        let before = kstart[i] + (kstart[n + i] - kstart[n]) + (kstart[2u * n + i] - kstart[2u * n]);
        k = kstart[3u * n] + i - before;
    }
    var p = parts[i];
    if (r == 0u) {
        p.flags = p.flags & ~FLAG_FROZEN;
    } else {
        p.flags = p.flags | FLAG_FROZEN;
    }
    dst[k] = p;
}

@compute @workgroup_size(1)
fn tally() {
    let n = prm.n;
    counts[0] = kstart[n];
    counts[1] = kstart[2u * n] - kstart[n];
    counts[2] = kstart[3u * n] - kstart[2u * n];
    counts[3] = n - kstart[3u * n];
    info.n_active = kstart[2u * n];
}
