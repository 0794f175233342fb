//! What a kernel can report as gone wrong, defined once for both sides: each code becomes a
//! WGSL constant `ERR_<NAME>` in every kernel's source (`shader.rs` writes them before the
//! common module), and the host turns the key it reads back from `Info::err_key` into the
//! solver's error. A failing particle offers one key, its id above its code
//! (`(id << CODE_BITS) | code`), to an atomic minimum: the step reports the failing particle with
//! the smallest id together with its own error, whatever order the threads ran in.

use regolith_fsi::SolverError;
use regolith_fsi::rheology::RheologyError;

/// Bits of an error key that hold the code; the bits above hold the particle's id.
pub(crate) const CODE_BITS: u32 = 4;
/// The largest id a key holds: a particle with a larger id is reported with this one.
pub(crate) const MAX_KEY_ID: u32 = u32::MAX >> CODE_BITS;
/// The key of a step without error (no code uses the all-ones pattern, see the tests).
pub(crate) const NO_ERROR: u32 = u32::MAX;

/// The particle id and the code of an error key read back (`None` when no particle failed).
pub(crate) fn decode(key: u32) -> Option<(u32, u32)> {
    (key != NO_ERROR).then_some((key >> CODE_BITS, key & ((1 << CODE_BITS) - 1)))
}

/// A kernel's error, as the device stores it (the low bits of `Info::err_key`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[repr(u32)]
pub(crate) enum DeviceError {
    /// An elastic trial stress that is not finite.
    ElasticNonfinite = 1,
    /// A Drucker–Prager trial stress that is not finite.
    DpNonfinite = 2,
    /// A Modified Cam Clay trial state that is not finite.
    MccNonfiniteTrial = 3,
    /// A Modified Cam Clay preconsolidation pressure that is not positive.
    MccPc = 4,
    /// Modified Cam Clay moduli that are not positive at a plastic correction.
    MccModuli = 5,
    /// A Modified Cam Clay return mapping that did not converge.
    MccNoConvergence = 6,
    /// A Modified Cam Clay return mapping whose result is not finite.
    MccNonfiniteResult = 7,
    /// A position that is not finite.
    Position = 8,
    /// A velocity that is not finite.
    Velocity = 9,
    /// A density that is not finite.
    Density = 10,
}

impl DeviceError {
    /// Every error, in code order.
    pub(crate) const ALL: [DeviceError; 10] = [
        DeviceError::ElasticNonfinite,
        DeviceError::DpNonfinite,
        DeviceError::MccNonfiniteTrial,
        DeviceError::MccPc,
        DeviceError::MccModuli,
        DeviceError::MccNoConvergence,
        DeviceError::MccNonfiniteResult,
        DeviceError::Position,
        DeviceError::Velocity,
        DeviceError::Density,
    ];

    /// The name of its WGSL constant.
    pub(crate) fn wgsl_name(self) -> &'static str {
        match self {
            DeviceError::ElasticNonfinite => "ERR_ELASTIC_NONFINITE",
            DeviceError::DpNonfinite => "ERR_DP_NONFINITE",
            DeviceError::MccNonfiniteTrial => "ERR_MCC_NONFINITE_TRIAL",
            DeviceError::MccPc => "ERR_MCC_PC",
            DeviceError::MccModuli => "ERR_MCC_MODULI",
            DeviceError::MccNoConvergence => "ERR_MCC_NO_CONVERGENCE",
            DeviceError::MccNonfiniteResult => "ERR_MCC_NONFINITE_RESULT",
            DeviceError::Position => "ERR_POSITION",
            DeviceError::Velocity => "ERR_VELOCITY",
            DeviceError::Density => "ERR_DENSITY",
        }
    }

    /// The error of a code read back from the device (`None` for 0 and unknown codes).
    pub(crate) fn from_code(code: u32) -> Option<Self> {
        Self::ALL.into_iter().find(|e| *e as u32 == code)
    }

    /// The WGSL declarations of every code (one `const` line each) and of the key's layout
    /// (`ERR_CODE_BITS`, `ERR_MAX_ID`, `ERR_NONE`).
    pub(crate) fn wgsl_constants() -> String {
        let mut s: String =
            Self::ALL.iter().map(|e| format!("const {}: u32 = {}u;\n", e.wgsl_name(), *e as u32)).collect();
        s += &format!("const ERR_CODE_BITS: u32 = {CODE_BITS}u;\n");
        s += &format!("const ERR_MAX_ID: u32 = {MAX_KEY_ID}u;\n");
        s += &format!("const ERR_NONE: u32 = {NO_ERROR}u;\n");
        s
    }

    /// The solver's error for this code, met at `step` (ending at `time`) by `particle`.
    pub(crate) fn into_solver_error(self, step: u64, time: f64, particle: u32) -> SolverError {
        let rheology = |source| SolverError::Rheology { step, time, particle, source };
        let nonfinite = |what| SolverError::NonFinite { step, time, particle, what };
        match self {
            DeviceError::ElasticNonfinite => {
                rheology(RheologyError::NonFinite { model: "elastic", stage: "trial stress" })
            }
            DeviceError::DpNonfinite => {
                rheology(RheologyError::NonFinite { model: "drucker-prager", stage: "trial stress" })
            }
            DeviceError::MccNonfiniteTrial => rheology(RheologyError::NonFinite { model: "mcc", stage: "trial state" }),
            DeviceError::MccPc => rheology(RheologyError::InvalidState { model: "mcc", what: "p_c must be positive" }),
            DeviceError::MccModuli => rheology(RheologyError::InvalidState {
                model: "mcc",
                what: "elastic moduli must be positive for a plastic correction",
            }),
            DeviceError::MccNoConvergence => {
                rheology(RheologyError::NoConvergence { model: "mcc", stage: "return mapping" })
            }
            DeviceError::MccNonfiniteResult => {
                rheology(RheologyError::NonFinite { model: "mcc", stage: "return mapping" })
            }
            DeviceError::Position => nonfinite("position"),
            DeviceError::Velocity => nonfinite("velocity"),
            DeviceError::Density => nonfinite("density"),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every `ERR_…` name in `text`.
    fn names(text: &str) -> Vec<String> {
        let mut out = Vec::new();
        let mut rest = text;
        while let Some(i) = rest.find("ERR_") {
            let name: String =
                rest[i..].chars().take_while(|c| c.is_ascii_uppercase() || c.is_ascii_digit() || *c == '_').collect();
            out.push(name.clone());
            rest = &rest[i + name.len()..];
        }
        out
    }

    #[test]
    fn codes_are_distinct_nonzero_and_read_back() {
        for (k, e) in DeviceError::ALL.iter().enumerate() {
            assert_eq!(*e as u32, k as u32 + 1, "{e:?}: codes follow ALL's order from 1");
            assert_eq!(DeviceError::from_code(*e as u32), Some(*e));
            assert_eq!(names(e.wgsl_name()), [e.wgsl_name()]);
        }
        assert_eq!(DeviceError::from_code(0), None);
        assert_eq!(DeviceError::from_code(DeviceError::ALL.len() as u32 + 1), None);
        let consts = DeviceError::wgsl_constants();
        assert_eq!(consts.lines().count(), DeviceError::ALL.len() + 3);
        assert!(consts.contains("const ERR_DENSITY: u32 = 10u;"), "{consts}");
    }

    /// Every code fits the key's code bits without making the no-error pattern, and a key keeps
    /// the id and the code of one particle: the smallest key is the smallest id's.
    #[test]
    fn a_key_carries_one_particles_id_and_code_and_orders_by_id() {
        for e in DeviceError::ALL {
            assert!((e as u32) < (1 << CODE_BITS) - 1, "{e:?} does not fit {CODE_BITS} bits below all ones");
        }
        let key = |id: u32, e: DeviceError| (id.min(MAX_KEY_ID) << CODE_BITS) | e as u32;
        assert_eq!(decode(key(7, DeviceError::Velocity)), Some((7, DeviceError::Velocity as u32)));
        assert_eq!(decode(key(u32::MAX, DeviceError::MccPc)), Some((MAX_KEY_ID, DeviceError::MccPc as u32)));
        assert_eq!(decode(NO_ERROR), None);
        // Two particles fail: the smaller id wins with its own code, not the other's larger one.
        let keys = [key(12, DeviceError::Density), key(3, DeviceError::ElasticNonfinite)];
        assert_eq!(decode(keys[0].min(keys[1])), Some((3, DeviceError::ElasticNonfinite as u32)));
    }

    /// The kernels name only codes this enum defines, and none declares its own.
    #[test]
    fn every_code_a_kernel_names_is_defined_here() {
        // The codes and the key's layout constants, as written into every kernel's source.
        let defined = names(&DeviceError::wgsl_constants());
        let sources = [
            ("advance.wgsl", include_str!("kernels/advance.wgsl")),
            ("step_info.wgsl", include_str!("kernels/step_info.wgsl")),
            ("dp.wgsl", include_str!("kernels/dp.wgsl")),
            ("mcc.wgsl", include_str!("kernels/mcc.wgsl")),
            ("common.wgsl", include_str!("kernels/common.wgsl")),
            ("wet.wgsl", include_str!("kernels/wet.wgsl")),
            ("shader.rs", include_str!("shader.rs")),
        ];
        let mut used = 0;
        for (file, text) in sources {
            assert!(!text.contains("const ERR_"), "{file} declares an error code of its own");
            for n in names(text) {
                assert!(defined.contains(&n), "{file} names {n}, which error_code.rs does not define");
                used += 1;
            }
        }
        assert!(used >= DeviceError::ALL.len(), "the kernels name {used} codes");
    }
}
