// One record per soil particle with what its neighbours read (position, velocity, sigma/rho^2,
// volume, mass, density, wave speed), and its elastic moduli; the largest wave speed goes to
// `info.cmax`. CPU twin: `rates::pack_soil`.

@group(0) @binding(0) var<uniform> prm: Params;
@group(0) @binding(1) var<storage, read> parts: array<Particle>;
@group(0) @binding(2) var<storage, read> materials: array<Material>;
@group(0) @binding(3) var<storage, read_write> packed: array<Packed>;
@group(0) @binding(4) var<storage, read_write> moduli: array<vec2<f32>>;
@group(0) @binding(5) var<storage, read_write> info: Info;

@compute @workgroup_size(64)
fn pack(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = flat(gid);
    if (i >= info.n_active) { return; }
    let p = parts[i];
    let mat = materials[p.material];
    let sigma = load_sigma(p);
    let m = material_moduli(mat, sigma, p.sv);
    moduli[i] = m;
    let r = p.rho;
    let s = sym_scale(sigma, 1.0 / (r * r));
    let cs = sqrt((m.x + (4.0 / 3.0) * m.y) / mat.density);
    packed[i] = Packed(p.px, p.py, p.pz, p.vx, p.vy, p.vz, s.xx, s.yy, s.zz, s.xy, s.xz, s.yz, p.mass / r, p.mass, r, cs);
    // The time step follows the integrated (awake) particles only.
    if ((p.flags & FLAG_FROZEN) == 0u) { atomicMax(&info.cmax, max_bits(cs)); }
}
