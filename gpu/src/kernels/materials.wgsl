// Material records and the pressure-dependent moduli (MCC) or the reference ones. CPU twin:
// `Material::moduli`.

struct Material {
    model: u32, density: f32, bulk: f32, shear: f32,
    poisson: f32, mu_s: f32, mu_2: f32, i0: f32,
    grain_d: f32, grain_rho: f32, k: f32, m: f32,
    kappa: f32, lambda: f32, clamp: u32, clamp_lo: f32,
    clamp_hi: f32, pc_floor: f32, inv_perm: f32, grain_por: f32,
}

const MODEL_ELASTIC: u32 = 0u;
const MODEL_DP: u32 = 1u;
const MODEL_MCC: u32 = 2u;
const MODEL_WATER: u32 = 3u;

fn moduli_from_bulk_poisson(k: f32, nu: f32) -> vec2<f32> {
    return vec2<f32>(k, 3.0 * k * (1.0 - 2.0 * nu) / (2.0 * (1.0 + nu)));
}

fn material_moduli(mat: Material, sigma: Sym, sv: f32) -> vec2<f32> {
    if (HAS_MCC && mat.model == MODEL_MCC) {
        let p = sym_pressure(sigma);
        var k_law = 0.0;
        if (p > 0.0) { k_law = sv * p / mat.kappa; }
        var k = k_law;
        if (mat.clamp != 0u) { k = min(max(k_law, mat.clamp_lo * mat.bulk), mat.clamp_hi * mat.bulk); }
        return moduli_from_bulk_poisson(k, mat.poisson);
    }
    return vec2<f32>(mat.bulk, mat.shear);
}
