// Wet soil: the phase coupling of a water phase sharing space with the soil skeleton (mixture
// theory; the equations, the smoothed volume fractions and the midpoint slip are described in
// the CPU twin, `cpu::wet`). One evaluation runs, in order:
//   phases           each particle's phase, grain volume and 1/k            (`wet::phases`)
//   marker_solids    each marker's solid share and drag velocity            (`wet::marker_solids`)
//   porosity         water: porosity, pore pressure, partial stress;
//                    soil: saturation; both: own-phase velocity gradient   (`wet::porosity`)
//   soil_pressures   the pore pressure interpolated at each soil particle  (`wet::soil_pressures`)
//   wet_extrapolate  each marker's soil record (effective stress), water
//                    record (-p I) and pore pressure                        (`rates::extrapolate_markers`
//                                                                           twice, `wet::marker_pressures`)
//   wet_rates        same-phase pairs as the dry loop, cross-phase pairs
//                    through pore pressure and drag                         (`wet::wet_rates`)
//   wet_marker_forces  minus all of that on each marker                     (`wet::wet_marker_forces`)
// and `init_water` (the water's partial density and mass at the start, `CpuSph::init_water`) and
// `water_stress` (a water particle's stress is its pore pressure after a step) around them.
// Neighbours come from for_each_in_reach (the CPU's visiting order, see neighbour_loop.rs), so
// sums round alike. Each entry point has its own bind group layout with the bindings it uses.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read_write> packed: array<Packed>;
@group(0) @binding(2) var<storage, read> start: array<u32>;
@group(0) @binding(3) var<storage, read_write> m_packed: array<Packed>;
@group(0) @binding(4) var<storage, read_write> m_packed_w: array<Packed>;
@group(0) @binding(5) var<storage, read> m_start: array<u32>;
@group(0) @binding(6) var<storage, read> moduli: array<vec2<f32>>;
@group(0) @binding(7) var<storage, read_write> parts: array<Particle>;
@group(0) @binding(8) var<storage, read_write> rates: array<Rate>;
@group(0) @binding(9) var<storage, read_write> info: Info;
@group(0) @binding(10) var<storage, read> materials: array<Material>;
@group(0) @binding(11) var<storage, read_write> pore: array<Pore>;
@group(0) @binding(12) var<storage, read_write> m_pore: array<MarkerPore>;
@group(0) @binding(13) var<storage, read> markers: array<Marker>;
@group(0) @binding(14) var<storage, read> owner_perm: array<u32>;
@group(0) @binding(15) var<storage, read> m_order: array<u32>;
@group(0) @binding(16) var<storage, read_write> m_force: array<f32>;
@group(0) @binding(17) var<storage, read> owner_mu: array<f32>;

// What the coupling knows of a particle at a stage. water/vg/inv_k: its phase (soil: grain
// volume m / rho_g over the lattice sum, and 1/k; water: 0); n, p, cw, inv_sum: water's
// porosity, pore pressure (soil: interpolated), n^2 gamma_w and drag normaliser; sat: soil's
// saturation; g: the own-phase velocity gradient, by rows.
struct Pore {
    water: u32, vg: f32, inv_k: f32, n: f32,
    p: f32, cw: f32, inv_sum: f32, sat: f32,
    g00: f32, g01: f32, g02: f32,
    g10: f32, g11: f32, g12: f32,
    g20: f32, g21: f32, g22: f32,
}

// A marker's solid volume, mean 1/k and pore pressure, the velocity the water is dragged
// towards there, and whether its owner lets the water through.
struct MarkerPore { vg: f32, inv_k: f32, p: f32, vx: f32, vy: f32, vz: f32, permeable: u32 }

struct Rows { r0: vec3<f32>, r1: vec3<f32>, r2: vec3<f32> }

fn rows_of(q: Pore) -> Rows {
    return Rows(vec3<f32>(q.g00, q.g01, q.g02), vec3<f32>(q.g10, q.g11, q.g12), vec3<f32>(q.g20, q.g21, q.g22));
}

fn marker_x(m: Marker) -> vec3<f32> { return vec3<f32>(m.px, m.py, m.pz); }

fn tiny() -> f32 { return sqrt(F32_MIN_POS); }

// The phase-coupling force on a from b of the other phase (xyz, N) and the drag coefficient
// C V_a V_b W (w, kg/s): pore pressure and drag, one expression from either side (water
// operands first), so a pair's two evaluations are exact negatives. CPU twin: `wet::coupling`.
fn coupling(pa: Packed, pb: Packed, a_water: bool, dp: f32, cw: f32, vg: f32, inv_k: f32, inv_sum: f32, g: Rows) -> vec4<f32> {
    let r = packed_x(pa) - packed_x(pb);
    let r2 = dot(r, r);
    if (r2 >= prm.support2) { return vec4<f32>(0.0); }
    let rr = sqrt(r2);
    let gw = r * kernel_grad_factor(rr, prm.inv_h, prm.alpha);
    let w = kernel_w(rr, prm.inv_h, prm.alpha);
    var vw = pb.vol;
    var vs = pa.vol;
    if (a_water) { vw = pa.vol; vs = pb.vol; }
    let drag = cw * inv_k * (vw * vs) * (w * inv_sum);
    let slip = (packed_v(pa) - packed_v(pb)) - vec3<f32>(dot(g.r0, r), dot(g.r1, r), dot(g.r2, r)) * 0.5;
    let f = -(gw * (dp * vw * (vg * prm.lsum))) - slip * drag;
    return vec4<f32>(f, drag);
}

// Morris et al. (1997) laminar viscous force on a from b (N). CPU twin: `wet::laminar`.
fn laminar(pa: Packed, pb: Packed) -> vec3<f32> {
    let r = packed_x(pa) - packed_x(pb);
    let r2 = dot(r, r);
    if (r2 >= prm.support2) { return vec3<f32>(0.0); }
    let rgw = r2 * kernel_grad_factor(sqrt(r2), prm.inv_h, prm.alpha);
    let k = (pa.vol * pb.vol) * (prm.w_mu + prm.w_mu) * rgw / (r2 + prm.eta2);
    return (packed_v(pa) - packed_v(pb)) * k;
}

// The water's delta-SPH density diffusion between a and b, less its hydrostatic part (before
// the factor delta h c n_a). CPU twin: `wet::density_diffusion`.
fn density_diffusion(pa: Packed, pb: Packed, psi_a: f32, psi_b: f32) -> f32 {
    let r = packed_x(pa) - packed_x(pb);
    let r2 = dot(r, r);
    if (r2 >= prm.support2) { return 0.0; }
    let g = vec3<f32>(prm.g_x, prm.g_y, prm.g_z);
    let hydro = prm.w_rest * dot(g, r) / (prm.w_c * prm.w_c);
    let rgw = r2 * kernel_grad_factor(sqrt(r2), prm.inv_h, prm.alpha);
    return 2.0 * pb.vol * (psi_a - psi_b - hydro) * rgw / (r2 + prm.eta2);
}

@compute @workgroup_size(64)
fn phases(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active) { return; }
    let mat = materials[parts[i].material];
    if (mat.model == MODEL_WATER) {
        pore[i].water = 1u;
        pore[i].vg = 0.0;
        pore[i].inv_k = 0.0;
    } else {
        pore[i].water = 0u;
        pore[i].vg = parts[i].mass / mat.grain_por * prm.inv_lsum;
        pore[i].inv_k = mat.inv_perm;
    }
}

@compute @workgroup_size(64)
fn marker_solids(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = flat(gid);
    if (k >= m_start[prm.n_cells]) { return; }
    let mk = markers[k];
    let xw = marker_x(mk);
    var sw = 0.0;
    var sf = 0.0;
    var sk = 0.0;
    var sv = vec3<f32>(0.0);
    let c = cell_coords(xw);
    if (c.x >= 0) {
        let rc = reach_of(c);
        for_each_in_reach(j, start, rc) {
            if (pore[j].water != 0u) { continue; }
            let pa = packed[j];
            let r = xw - packed_x(pa);
            let r2 = dot(r, r);
            if (r2 >= prm.support2) { continue; }
            let w = kernel_w(sqrt(r2), prm.inv_h, prm.alpha);
            sw += w;
            sf += pore[j].vg / pa.vol * w;
            sk += pore[j].inv_k * w;
            sv += packed_v(pa) * w;
        }
    }
    let perm = owner_perm[mk.owner];
    if (sw > tiny()) {
        let v = sv * (1.0 / sw);
        m_pore[k] = MarkerPore(prm.m_volume * sf / sw, sk / sw, 0.0, v.x, v.y, v.z, perm);
    } else {
        m_pore[k] = MarkerPore(0.0, 0.0, 0.0, mk.vx, mk.vy, mk.vz, perm);
    }
}

@compute @workgroup_size(64)
fn porosity(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active) { return; }
    let pa = packed[i];
    let xa = packed_x(pa);
    let water = pore[i].water;
    var solid = 0.0;
    var vw = 0.0;
    var vs = 0.0;
    var g0 = vec3<f32>(0.0);
    var g1 = vec3<f32>(0.0);
    var g2 = vec3<f32>(0.0);
    let c = cell_coords(xa);
    if (c.x >= 0) {
        let rc = reach_of(c);
        for_each_in_reach(j, start, rc) {
            if (j == i) { continue; }
            let pb = packed[j];
            let r = xa - packed_x(pb);
            let r2 = dot(r, r);
            if (r2 >= prm.support2) { continue; }
            let rr = sqrt(r2);
            let w = kernel_w(rr, prm.inv_h, prm.alpha);
            let wb = pore[j].water;
            if (wb == water) {
                // (v_b - v_a) (x) r V_b F: the own-phase velocity gradient.
                let u = packed_v(pb) - packed_v(pa);
                let v = r * (pb.vol * kernel_grad_factor(rr, prm.inv_h, prm.alpha));
                g0 += v * u.x;
                g1 += v * u.y;
                g2 += v * u.z;
            }
            if (wb != 0u) {
                vw += pb.vol * w;
            } else {
                solid += pore[j].vg * w;
                vs += pb.vol * w;
            }
        }
        if (water != 0u) {
            for_each_in_reach(k, m_start, rc) {
                let mp = m_pore[k];
                if (mp.permeable != 0u) { continue; }
                let r = xa - marker_x(markers[k]);
                let r2 = dot(r, r);
                if (r2 >= prm.support2) { continue; }
                let w = kernel_w(sqrt(r2), prm.inv_h, prm.alpha);
                solid += mp.vg * w;
                // Markers drag the water where they hold soil.
                if (mp.inv_k > 0.0) { vs += prm.m_volume * w; }
            }
        }
    }
    pore[i].g00 = g0.x; pore[i].g01 = g0.y; pore[i].g02 = g0.z;
    pore[i].g10 = g1.x; pore[i].g11 = g1.y; pore[i].g12 = g1.z;
    pore[i].g20 = g2.x; pore[i].g21 = g2.y; pore[i].g22 = g2.z;
    if (water != 0u) {
        // Inside the soil the Shepard mean of its solid fraction; at a surface the smoothed
        // volume fraction over chi (see `wet::porosity`).
        let presence = max(vs * prm.inv_lsum, prm.full_support);
        let n = max(1.0 - solid / presence, MIN_POROSITY);
        let p = max(prm.w_c * prm.w_c * (pa.rho / n - prm.w_rest), 0.0);
        let s = -p / (pa.rho * pa.rho);
        packed[i].sxx = s; packed[i].syy = s; packed[i].szz = s;
        packed[i].sxy = 0.0; packed[i].sxz = 0.0; packed[i].syz = 0.0;
        var inv_sum = prm.inv_lsum;
        if (prm.drag_particle != 0u) {
            inv_sum = 0.0;
            if (vs > tiny()) { inv_sum = 1.0 / vs; }
        }
        pore[i].n = n;
        pore[i].p = p;
        pore[i].cw = n * n * prm.w_gamma;
        pore[i].inv_sum = inv_sum;
        pore[i].sat = 0.0;
    } else {
        // The particle's own volume is in the soil sum (W(0)), so it is never empty.
        vs += pa.vol * kernel_w(0.0, prm.inv_h, prm.alpha);
        pore[i].n = 0.0;
        pore[i].p = 0.0;
        pore[i].cw = 0.0;
        pore[i].inv_sum = 0.0;
        pore[i].sat = min(vw / vs, 1.0);
    }
}

@compute @workgroup_size(64)
fn soil_pressures(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active) { return; }
    if (pore[i].water != 0u) { return; }
    let xa = packed_x(packed[i]);
    var sw = 0.0;
    var sp = 0.0;
    let c = cell_coords(xa);
    if (c.x >= 0) {
        let rc = reach_of(c);
        for_each_in_reach(j, start, rc) {
            if (j == i || pore[j].water == 0u) { continue; }
            let pb = packed[j];
            let r = xa - packed_x(pb);
            let r2 = dot(r, r);
            if (r2 >= prm.support2) { continue; }
            let w = pb.vol * kernel_w(sqrt(r2), prm.inv_h, prm.alpha);
            sw += w;
            sp += pore[j].p * w;
        }
    }
    var p = 0.0;
    if (sw > tiny()) { p = sp / sw; }
    pore[i].p = p;
}

// A marker record from the sums of one phase (Adami et al. 2012, with the owner's wall
// contact), or the reference record where that phase has no particle in reach.
fn wall_record(xw: vec3<f32>, mk: Marker, sw: f32, sv: vec3<f32>, ss: Sym, srr: vec3<f32>, srho: f32, scs: f32, ref_rho: f32, ref_cs: f32) -> Packed {
    let vb = vec3<f32>(mk.vx, mk.vy, mk.vz);
    if (sw > tiny()) {
        let inv = 1.0 / sw;
        let rho = srho * inv;
        let g = vec3<f32>(prm.g_x, prm.g_y, prm.g_z);
        let dp = dot(g - vec3<f32>(mk.ax, mk.ay, mk.az), srr) * inv;
        let w = wall_state(mk, owner_mu[mk.owner], rho * scs * inv, sv * inv, sym_sub(sym_scale(ss, inv), sym_iso(dp)));
        let s = sym_scale(w.s, 1.0 / (rho * rho));
        let v = w.v;
        return Packed(xw.x, xw.y, xw.z, v.x, v.y, v.z, s.xx, s.yy, s.zz, s.xy, s.xz, s.yz,
            prm.m_volume, rho * prm.m_volume, rho, scs * inv);
    }
    return Packed(xw.x, xw.y, xw.z, vb.x, vb.y, vb.z, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0,
        prm.m_volume, ref_rho * prm.m_volume, ref_rho, ref_cs);
}

@compute @workgroup_size(64)
fn wet_extrapolate(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = flat(gid);
    if (k >= m_start[prm.n_cells]) { return; }
    let mk = markers[k];
    let xw = marker_x(mk);
    // Soil: its effective stress, stepped with the buoyant density rho - rho_w (1 - n) sat.
    var sw = 0.0;
    var sv = vec3<f32>(0.0);
    var ss = sym_zero();
    var srr = vec3<f32>(0.0);
    var srho = 0.0;
    var scs = 0.0;
    // Water: -p I stepped with its intrinsic density, and the pore pressure itself.
    var ww = 0.0;
    var wv = vec3<f32>(0.0);
    var ws = 0.0;
    var wrr = vec3<f32>(0.0);
    var wrho = 0.0;
    var wcs = 0.0;
    var pp = 0.0;
    var pr = vec3<f32>(0.0);
    let c = cell_coords(xw);
    if (c.x >= 0) {
        let rc = reach_of(c);
        for_each_in_reach(j, start, rc) {
            let pa = packed[j];
            let r = xw - packed_x(pa);
            let r2 = dot(r, r);
            if (r2 >= prm.support2) { continue; }
            let w = kernel_w(sqrt(r2), prm.inv_h, prm.alpha);
            let q = pore[j];
            if (q.water == 0u) {
                let rho_step = pa.rho - prm.w_rest * q.vg / pa.vol * q.sat;
                sw += w;
                sv += packed_v(pa) * w;
                ss = sym_add(ss, sym_scale(load_sigma(parts[j]), w));
                srr += r * (rho_step * w);
                srho += pa.rho * w;
                scs += pa.cs * w;
            } else {
                ww += w;
                wv += packed_v(pa) * w;
                ws += -q.p * w;
                wrr += r * ((pa.rho / q.n) * w);
                wrho += pa.rho * w;
                wcs += pa.cs * w;
                pp += q.p * w;
                pr += r * w;
            }
        }
    }
    m_packed[k] = wall_record(xw, mk, sw, sv, ss, srr, srho, scs, prm.ref_rho, prm.ref_cs);
    m_packed_w[k] = wall_record(xw, mk, ww, wv, sym_iso(ws), wrr, wrho, wcs, prm.w_rest, prm.w_c);
    var p = 0.0;
    if (ww > tiny()) {
        let g = vec3<f32>(prm.g_x, prm.g_y, prm.g_z);
        p = max((pp + prm.w_rest * dot(g - vec3<f32>(mk.ax, mk.ay, mk.az), pr)) / ww, 0.0);
    }
    m_pore[k].p = p;
}

@compute @workgroup_size(64)
fn wet_rates(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active) { return; }
    let pa = packed[i];
    let xa = packed_x(pa);
    let qa = pore[i];
    let a_water = qa.water != 0u;
    let ga = rows_of(qa);
    var s = Acc(0.0, vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0), sym_zero(), vec3<f32>(0.0), vec3<f32>(0.0));
    var f = vec3<f32>(0.0);
    var drag = 0.0;
    var diffusion = 0.0;
    var pairs = 0u;
    var contact = false;
    let c = cell_coords(xa);
    if (c.x >= 0) {
        let rc = reach_of(c);
        for_each_in_reach(j, start, rc) {
            if (j == i) { continue; }
            let pb = packed[j];
            let d = xa - packed_x(pb);
            if (dot(d, d) >= prm.radius2) { continue; }
            pairs++;
            let qb = pore[j];
            if (qb.water == qa.water) {
                visit(&s, pa, pb, true);
                if (a_water) {
                    if (prm.w_mu > 0.0) { f += laminar(pa, pb); }
                    diffusion += density_diffusion(pa, pb, pa.rho / qa.n, pb.rho / qb.n);
                }
            } else {
                let gb = rows_of(qb);
                let g = Rows(ga.r0 + gb.r0, ga.r1 + gb.r1, ga.r2 + gb.r2);
                var k: vec4<f32>;
                if (a_water) {
                    k = coupling(pa, pb, true, qa.p - qb.p, qa.cw, qb.vg, qb.inv_k, qa.inv_sum, g);
                } else {
                    k = coupling(pa, pb, false, qb.p - qa.p, qb.cw, qa.vg, qa.inv_k, qb.inv_sum, g);
                }
                f += k.xyz;
                drag += k.w;
            }
        }
        let zero = Rows(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
        for_each_in_reach(k, m_start, rc) {
            var rec = m_packed[k];
            if (a_water) { rec = m_packed_w[k]; }
            let d = xa - packed_x(rec);
            let d2 = dot(d, d);
            if (d2 >= prm.radius2) { continue; }
            pairs++;
            let mp = m_pore[k];
            // Water passes through a permeable owner's markers.
            if (a_water && mp.permeable != 0u) { continue; }
            if (d2 < prm.support2) { contact = true; }
            visit(&s, pa, rec, false);
            // The marker as the other phase: soil moving with the soil beside it for
            // the water, the extrapolated pore pressure for the soil.
            var wall = rec;
            wall.vx = mp.vx; wall.vy = mp.vy; wall.vz = mp.vz;
            var q: vec4<f32>;
            if (a_water) {
                q = coupling(pa, wall, true, qa.p - mp.p, qa.cw, mp.vg, mp.inv_k, qa.inv_sum, zero);
            } else {
                q = coupling(pa, wall, false, mp.p - qa.p, 0.0, qa.vg, 0.0, 0.0, zero);
            }
            f += q.xyz;
            drag += q.w;
        }
    }
    let l0 = s.l0;
    let l1 = s.l1;
    let l2 = s.l2;
    let d = Sym(l0.x, l1.y, l2.z, 0.5 * (l0.y + l1.x), 0.5 * (l0.z + l2.x), 0.5 * (l1.z + l2.y));
    let spin = vec3<f32>(0.5 * (l0.y - l1.x), 0.5 * (l0.z - l2.x), 0.5 * (l1.z - l2.y));
    let m = moduli[i];
    var ds = sym_zero();
    if (!a_water) { ds = jaumann(load_sigma(parts[i]), d, spin, m); }
    let inv_m = 1.0 / pa.mass;
    var drho = s.drho * pa.rho;
    if (a_water) { drho += DELTA_SPH * prm.h * prm.w_c * qa.n * diffusion; }
    let g = vec3<f32>(prm.g_x, prm.g_y, prm.g_z);
    let acc = s.acc + f * inv_m + g;
    var fs = rates[i].fs;
    if (FS) {
        fs = sym_min_eigenvalue(s.fs);
        var flags = 0u;
        if (!contact && fs < prm.fs_threshold) { flags |= FLAG_FREE; }
        if (fs < prm.detach_threshold) { flags |= FLAG_DETACHED; }
        parts[i].flags = flags;
        atomicAdd(&info.pairs, pairs);
        atomicMax(&info.drag, max_bits(drag * inv_m));
    }
    rates[i] = Rate(drho, acc.x, acc.y, acc.z,
        ds.xx, ds.yy, ds.zz, ds.xy, ds.xz, ds.yz,
        d.xx, d.yy, d.zz, d.xy, d.xz, d.yz,
        s.xs.x, s.xs.y, s.xs.z, s.gc.x, s.gc.y, s.gc.z,
        fs, m.x, m.y, 0.0);
}

@compute @workgroup_size(64)
fn wet_marker_forces(@builtin(global_invocation_id) gid: vec3<u32>) {
    let k = flat(gid);
    if (k >= m_start[prm.n_cells]) { return; }
    let ws = m_packed[k];
    let ww = m_packed_w[k];
    let mp = m_pore[k];
    let xw = packed_x(ws);
    let zero = Rows(vec3<f32>(0.0), vec3<f32>(0.0), vec3<f32>(0.0));
    var f = vec3<f32>(0.0);
    let c = cell_coords(xw);
    if (c.x >= 0) {
        let rc = reach_of(c);
        for_each_in_reach(j, start, rc) {
            let q = pore[j];
            let water = q.water != 0u;
            if (water && mp.permeable != 0u) { continue; }
            let pa = packed[j];
            var pw = ws;
            if (water) { pw = ww; }
            let r = packed_x(pa) - xw;
            let r2 = dot(r, r);
            if (r2 >= prm.support2) { continue; }
            let gw = r * kernel_grad_factor(sqrt(r2), prm.inv_h, prm.alpha);
            let vab = packed_v(pa) - packed_v(pw);
            f -= pair_term(pa, pw, r, r2, gw, vab) * (pa.mass * pw.mass);
            var wall = pw;
            wall.vx = mp.vx; wall.vy = mp.vy; wall.vz = mp.vz;
            var e: vec4<f32>;
            if (water) {
                e = coupling(pa, wall, true, q.p - mp.p, q.cw, mp.vg, mp.inv_k, q.inv_sum, zero);
            } else {
                e = coupling(pa, wall, false, mp.p - q.p, 0.0, q.vg, 0.0, 0.0, zero);
            }
            f -= e.xyz;
        }
    }
    let o = m_order[k];
    m_force[3u * o] = f.x;
    m_force[3u * o + 1u] = f.y;
    m_force[3u * o + 2u] = f.z;
}

@compute @workgroup_size(64)
fn init_water(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active) { return; }
    if (pore[i].water == 0u) { return; }
    // Each water particle starts with the volume of its lattice cell, m / rho = d0^3, and the
    // partial density n rho_w(p) of the pore pressure it was given.
    let p = max(sym_pressure(load_sigma(parts[i])), 0.0);
    let rho = pore[i].n * (prm.w_rest + p / (prm.w_c * prm.w_c));
    parts[i].rho = rho;
    parts[i].mass = rho * prm.m_volume;
}

@compute @workgroup_size(64)
fn water_stress(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active) { return; }
    if (pore[i].water == 0u) { return; }
    let p = -pore[i].p;
    parts[i].sxx = p; parts[i].syy = p; parts[i].szz = p;
    parts[i].sxy = 0.0; parts[i].sxz = 0.0; parts[i].syz = 0.0;
}
