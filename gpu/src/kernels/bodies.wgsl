// The device side of the body exchange. `place`: every body marker's position, velocity and
// acceleration from its body's state (rigid motion), from the body-frame positions kept on the
// device, so only the body states go up. `wrench`: one workgroup per body sums the force on its
// markers and the torque about the body's reference point (its centre of mass when placed), so
// only per-body wrenches come down. CPU twins: `BodyKinematics::point`,
// `SphSolver::body_wrenches`.

struct Body {
    qx: f32, qy: f32, qz: f32, qw: f32,
    ox: f32, oy: f32, oz: f32, cx: f32,
    cy: f32, cz: f32, vx: f32, vy: f32,
    vz: f32, wx: f32, wy: f32, wz: f32,
    ax: f32, ay: f32, az: f32, alx: f32,
    aly: f32, alz: f32, first: u32, count: u32,
}

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> bodies: array<Body>;
@group(0) @binding(2) var<storage, read> locals: array<f32>;
@group(0) @binding(3) var<storage, read_write> markers: array<Marker>;
@group(0) @binding(4) var<storage, read> m_force: array<f32>;
@group(0) @binding(5) var<storage, read_write> wrenches: array<f32>;

@compute @workgroup_size(64)
fn place(@builtin(global_invocation_id) gid: vec3<u32>, @builtin(workgroup_id) wg: vec3<u32>) {
    // Grid: x over a body's markers, y over bodies.
    let b = bodies[wg.y];
    let i = gid.x;
    if (i >= b.count) { return; }
    let j = b.first + i;
    let l = vec3<f32>(locals[3u * j], locals[3u * j + 1u], locals[3u * j + 2u]);
    let u = vec3<f32>(b.qx, b.qy, b.qz);
    let t = 2.0 * cross(u, l);
    let x = vec3<f32>(b.ox, b.oy, b.oz) + (l + b.qw * t + cross(u, t));
    let r = x - vec3<f32>(b.cx, b.cy, b.cz);
    let w = vec3<f32>(b.wx, b.wy, b.wz);
    let wr = cross(w, r);
    let v = vec3<f32>(b.vx, b.vy, b.vz) + wr;
    let a = vec3<f32>(b.ax, b.ay, b.az) + cross(vec3<f32>(b.alx, b.aly, b.alz), r) + cross(w, wr);
    var m = markers[j];
    m.px = x.x; m.py = x.y; m.pz = x.z;
    m.vx = v.x; m.vy = v.y; m.vz = v.z;
    m.ax = a.x; m.ay = a.y; m.az = a.z;
    markers[j] = m;
}

var<workgroup> part: array<vec3<f32>, 128>;

@compute @workgroup_size(64)
fn wrench(@builtin(workgroup_id) wg: vec3<u32>, @builtin(local_invocation_id) lid: vec3<u32>) {
    let b = bodies[wg.x];
    let c = vec3<f32>(b.cx, b.cy, b.cz);
    var f = vec3<f32>(0.0);
    var t = vec3<f32>(0.0);
    for (var i = lid.x; i < b.count; i += 64u) {
        let j = b.first + i;
        let fj = vec3<f32>(m_force[3u * j], m_force[3u * j + 1u], m_force[3u * j + 2u]);
        let m = markers[j];
        f += fj;
        t += cross(vec3<f32>(m.px, m.py, m.pz) - c, fj);
    }
    part[lid.x] = f;
    part[64u + lid.x] = t;
    for (var s = 32u; s > 0u; s >>= 1u) {
        workgroupBarrier();
        if (lid.x < s) {
            part[lid.x] += part[lid.x + s];
            part[64u + lid.x] += part[64u + lid.x + s];
        }
    }
    workgroupBarrier();
    if (lid.x == 0u) {
        let o = 6u * wg.x;
        wrenches[o] = part[0].x;
        wrenches[o + 1u] = part[0].y;
        wrenches[o + 2u] = part[0].z;
        wrenches[o + 3u] = part[64].x;
        wrenches[o + 4u] = part[64].y;
        wrenches[o + 5u] = part[64].z;
    }
}
