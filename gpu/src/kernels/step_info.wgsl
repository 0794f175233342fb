// Step bookkeeping: `reset` clears the step's maxima and error slot, `maxima` takes the
// largest speed and acceleration after the first stage, `choose_dt` sets the step
// dt = C min(h / (c_max + |v|max), sqrt(h / |a|max)) (or the fixed step), at most the largest
// step allowed and the host's limit; in a wet scene also at most 1 / lambda, the largest drag
// rate of the first stage. CPU twin: `CpuSph::choose_dt`.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> parts: array<Particle>;
@group(0) @binding(2) var<storage, read> rates: array<Rate>;
@group(0) @binding(3) var<storage, read_write> info: Info;

@compute @workgroup_size(1)
fn reset() {
    atomicStore(&info.cmax, 0u);
    atomicStore(&info.vmax, 0u);
    atomicStore(&info.amax, 0u);
    atomicStore(&info.pairs, 0u);
    atomicStore(&info.err_key, ERR_NONE);
    atomicStore(&info.vmax_end, 0u);
    atomicStore(&info.amax_end, 0u);
    atomicStore(&info.rarefied, 0u);
    atomicStore(&info.drag, 0u);
    atomicStore(&info.uncovered, 0u);
}

@compute @workgroup_size(64)
fn maxima(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active) { return; }
    let p = parts[i];
    if ((p.flags & FLAG_FROZEN) != 0u) { return; }
    let r = rates[i];
    atomicMax(&info.vmax, max_bits(length(vec3<f32>(p.vx, p.vy, p.vz))));
    atomicMax(&info.amax, max_bits(length(vec3<f32>(r.ax, r.ay, r.az))));
}

@compute @workgroup_size(1)
fn choose_dt() {
    var dt = prm.dt_fixed;
    if (ADAPTIVE) {
        let cmax = max(prm.ref_cs, bitcast<f32>(atomicLoad(&info.cmax)));
        let vmax = bitcast<f32>(atomicLoad(&info.vmax));
        let amax = bitcast<f32>(atomicLoad(&info.amax));
        dt = prm.cfl * prm.h / (cmax + vmax);
        if (amax > 0.0) { dt = min(dt, prm.cfl * sqrt(prm.h / amax)); }
        // Explicit drag (wet scenes): stable below 2 / lambda.
        let lambda = bitcast<f32>(atomicLoad(&info.drag));
        if (lambda > 0.0) { dt = min(dt, 1.0 / lambda); }
        dt = min(dt, prm.dt_max);
    }
    info.dt = min(dt, info.max_dt);
}
