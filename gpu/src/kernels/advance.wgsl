// Time integration of the soil with the plastic correction. STAGE: from the state at t over
// h = dt/2 into the midpoint arrays. Otherwise from t over h = dt into the state (RK2 moves
// positions with the midpoint velocity; Euler with the new one), with XSPH, concentration
// shifting (off at the free surface, capped at 0.2 d0) and the checks that stop a run: a
// failed return mapping, or a non-finite position, velocity or density. Detached particles,
// and surface ones in the `Zero` mode, carry no stress. The density is held at
// RAREFIED_DENSITY x rho0 when continuity would take it lower (counted in `info.rarefied`;
// water, whose density is partial, at RAREFIED_DENSITY x MIN_POROSITY x rho0).
// CPU twin: `CpuSph::advance`, `cpu::correct` and `cpu::at_least`.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read_write> parts: array<Particle>;
@group(0) @binding(2) var<storage, read_write> stage: array<Particle>;
@group(0) @binding(3) var<storage, read> rates: array<Rate>;
@group(0) @binding(4) var<storage, read> materials: array<Material>;
@group(0) @binding(5) var<storage, read_write> info: Info;

// The error codes are written before the common module from `DeviceError` (error_code.rs).

struct Corrected { s: Sym, pc: f32, sv: f32 }

fn rate_d(r: Rate) -> Sym { return Sym(r.dxx, r.dyy, r.dzz, r.dxy, r.dxz, r.dyz); }
fn rate_ds(r: Rate) -> Sym { return Sym(r.dsxx, r.dsyy, r.dszz, r.dsxy, r.dsxz, r.dsyz); }

fn correct(mat: Material, sigma: Sym, pc: f32, sv: f32, r: Rate, h: f32, stress_free: bool, err: ptr<function, u32>) -> Corrected {
    var out: Corrected;
    out.pc = pc;
    let d = rate_d(r);
    if (stress_free) {
        out.s = sym_zero();
    } else {
        let trial = sym_add(sigma, sym_scale(rate_ds(r), h));
        var pc_new = pc;
        out.s = material_correct(mat, trial, &pc_new, sv, vec2<f32>(r.bulk, r.shear), d, err);
        out.pc = pc_new;
    }
    out.sv = sv * exp(sym_trace(d) * h);
    return out;
}

// x, or floor when x is below it; NaN stays NaN for the density check.
fn at_least(x: f32, floor: f32) -> f32 {
    return select(x, floor, x < floor);
}

// The density below which a particle of `mat` is held (CPU twin: `cpu::density_floor`).
fn density_floor(mat: Material) -> f32 {
    if (WET && mat.model == MODEL_WATER) { return mat.density * RAREFIED_DENSITY * MIN_POROSITY; }
    return mat.density * RAREFIED_DENSITY;
}

// Offers the particle's error key: the step keeps the smallest id with its own code.
fn fail(id: u32, code: u32) {
    atomicMin(&info.err_key, (min(id, ERR_MAX_ID) << ERR_CODE_BITS) | code);
}

@compute @workgroup_size(64)
fn advance(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active) { return; }
    var p = parts[i];
    if ((p.flags & FLAG_FROZEN) != 0u) {
        // Extended (frozen) soil reads the same state at both stages.
        if (STAGE) { stage[i] = p; }
        return;
    }
    let r = rates[i];
    let mat = materials[p.material];
    let free = (p.flags & FLAG_FREE) != 0u;
    let stress_free = (p.flags & FLAG_DETACHED) != 0u || (ZERO_SURFACE && free);
    let acc = vec3<f32>(r.ax, r.ay, r.az);
    let xs = vec3<f32>(r.xsx, r.xsy, r.xsz);
    let pos = vec3<f32>(p.px, p.py, p.pz);
    let vel = vec3<f32>(p.vx, p.vy, p.vz);
    var err = 0u;
    if (STAGE) {
        let h = 0.5 * info.dt;
        let sv = vel + acc * h;
        let sp = pos + (vel + xs * prm.xsph_eps) * h;
        let c = correct(mat, load_sigma(p), p.pc, p.sv, r, h, stress_free, &err);
        var q = p;
        q.px = sp.x; q.py = sp.y; q.pz = sp.z;
        q.vx = sv.x; q.vy = sv.y; q.vz = sv.z;
        q.rho = at_least(p.rho + r.drho * h, density_floor(mat));
        q.sxx = c.s.xx; q.syy = c.s.yy; q.szz = c.s.zz; q.sxy = c.s.xy; q.sxz = c.s.xz; q.syz = c.s.yz;
        q.pc = c.pc;
        q.sv = c.sv;
        stage[i] = q;
        if (err != 0u) { fail(p.id, err); }
        return;
    }
    let h = info.dt;
    let v = vel + acc * h;
    var v_move = v;
    if (RK2) { v_move = vec3<f32>(stage[i].vx, stage[i].vy, stage[i].vz); }
    var dx = (v_move + xs * prm.xsph_eps) * h;
    if (PPST && !free) {
        var d = vec3<f32>(r.gcx, r.gcy, r.gcz) * (-(prm.shift * length(v_move) * h));
        let len = length(d);
        if (len > prm.max_shift) { d = d * (prm.max_shift / len); }
        dx += d;
    }
    let np = pos + dx;
    let floor = density_floor(mat);
    let rho = at_least(p.rho + r.drho * h, floor);
    if (rho <= floor) { atomicAdd(&info.rarefied, 1u); }
    let c = correct(mat, load_sigma(p), p.pc, p.sv, r, h, stress_free, &err);
    p.px = np.x; p.py = np.y; p.pz = np.z;
    p.vx = v.x; p.vy = v.y; p.vz = v.z;
    p.rho = rho;
    p.sxx = c.s.xx; p.syy = c.s.yy; p.szz = c.s.zz; p.sxy = c.s.xy; p.sxz = c.s.xz; p.syz = c.s.yz;
    p.pc = c.pc;
    p.sv = c.sv;
    parts[i] = p;
    if (err == 0u && !finite3(np)) { err = ERR_POSITION; }
    if (err == 0u && !finite3(v)) { err = ERR_VELOCITY; }
    if (err == 0u && !(finite(rho) && rho > 0.0)) { err = ERR_DENSITY; }
    if (err != 0u) { fail(p.id, err); }
    atomicMax(&info.vmax_end, max_bits(length(v)));
    atomicMax(&info.amax_end, max_bits(length(acc)));
}
