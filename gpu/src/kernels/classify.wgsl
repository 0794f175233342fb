// The active region's classification on the device (see `regolith_fsi::active`), run as
//   roles     (here): awake inside a box grown by the travel allowance or faster than the
//             sleep speed, asleep otherwise, outside off the grid; awake particles mark the
//             cells they hold;
//   dilate    (dilate.wgsl, six times): the held cells grown by one cell along each axis in
//             turn are the cells awake particles may be in (read by `cover`); grown again by
//             the search reach, the cells whose asleep particles are extended (`near`);
//   mark      (here): extended roles, and a 1 in the role's segment of `keys` (three segments
//             of `n`: awake, extended, asleep);
//   scan      (scan.wgsl): `keys` into `kstart`, where each particle goes;
//   place, tally (partition.wgsl): each record to its place, and the counts.
// A particle keeps its earlier order within its role, as the host's counting does.
// CPU twin: `ActiveRegion::classify` (the box test and the speed are f32 here, f64 there: a
// role can differ only for a particle within f32 round-off of a box face or the sleep speed).

struct Box {
    cx: f32, cy: f32, cz: f32, h0: f32,
    a0x: f32, a0y: f32, a0z: f32, h1: f32,
    a1x: f32, a1y: f32, a1z: f32, h2: f32,
    a2x: f32, a2y: f32, a2z: f32, pad: f32,
}

// The boxes in use, the sleep speed squared (m²/s²) and the travel allowance (m).
struct Classify { n_boxes: u32, v2: f32, travel: f32, pad: u32 }

const AWAKE: u32 = 0u;
const EXTENDED: u32 = 1u;
const ASLEEP: u32 = 2u;
const OUTSIDE: u32 = 3u;

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<uniform> cls: Classify;
@group(0) @binding(2) var<storage, read> parts: array<Particle>;
@group(0) @binding(3) var<storage, read> boxes: array<Box>;
@group(0) @binding(4) var<storage, read_write> role: array<u32>;
@group(0) @binding(5) var<storage, read_write> cell_of: array<u32>;
@group(0) @binding(6) var<storage, read_write> held: array<atomic<u32>>;
@group(0) @binding(7) var<storage, read> near: array<u32>;
@group(0) @binding(8) var<storage, read_write> keys: array<u32>;

fn in_box(b: Box, p: vec3<f32>) -> bool {
    let d = p - vec3<f32>(b.cx, b.cy, b.cz);
    let g = cls.travel;
    return abs(dot(d, vec3<f32>(b.a0x, b.a0y, b.a0z))) <= b.h0 + g
        && abs(dot(d, vec3<f32>(b.a1x, b.a1y, b.a1z))) <= b.h1 + g
        && abs(dot(d, vec3<f32>(b.a2x, b.a2y, b.a2z))) <= b.h2 + g;
}

@compute @workgroup_size(64)
fn roles(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= prm.n) { return; }
    let pa = parts[i];
    let p = vec3<f32>(pa.px, pa.py, pa.pz);
    let c = cell_coords(p);
    if (c.x < 0) {
        role[i] = OUTSIDE;
        cell_of[i] = prm.n_cells;
        return;
    }
    let cell = cell_linear(u32(c.x), u32(c.y), u32(c.z));
    cell_of[i] = cell;
    let v = vec3<f32>(pa.vx, pa.vy, pa.vz);
    var awake = dot(v, v) > cls.v2;
    for (var k = 0u; k < cls.n_boxes && !awake; k++) {
        awake = in_box(boxes[k], p);
    }
    if (awake) {
        role[i] = AWAKE;
        atomicStore(&held[cell], 1u);
    } else {
        role[i] = ASLEEP;
    }
}

@compute @workgroup_size(64)
fn mark(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= prm.n) { return; }
    var r = role[i];
    if (r == ASLEEP && near[cell_of[i]] != 0u) {
        r = EXTENDED;
        role[i] = r;
    }
    if (r != OUTSIDE) { keys[r * prm.n + i] = 1u; }
}
