//! `soil_contact` of `[container]` and `[[bodies]]`: how soil slides along walls and bodies.
//!
//! ```toml
//! soil_contact = "rough"                 # no slip, adhesive for cohesive soil (the default)
//! soil_contact = "smooth"                # free slip
//! soil_contact = { friction = 0.35 }     # Coulomb: tangential traction ≤ μ × normal
//! ```

use regolith_fsi::config::WallContact;

/// Reads a `soil_contact` value; the message says what is allowed.
pub(super) fn parse_contact(v: &toml::Value) -> Result<WallContact, String> {
    const ALLOWED: &str = "allowed: \"rough\", \"smooth\" or { friction = μ } with μ ≥ 0";
    match v {
        toml::Value::String(s) if s == "rough" => Ok(WallContact::Rough),
        toml::Value::String(s) if s == "smooth" => Ok(WallContact::Smooth),
        toml::Value::Table(t) => {
            if let Some(k) = t.keys().find(|k| *k != "friction") {
                return Err(format!("unknown key `{k}`; {ALLOWED}"));
            }
            let mu = match t.get("friction") {
                Some(toml::Value::Float(f)) => *f,
                Some(toml::Value::Integer(i)) => *i as f64,
                Some(other) => return Err(format!("friction must be a number (got {other}); {ALLOWED}")),
                None => return Err(format!("the table has no friction; {ALLOWED}")),
            };
            if !(mu.is_finite() && mu >= 0.0) {
                return Err(format!("friction must be finite and ≥ 0 (got {mu})"));
            }
            Ok(WallContact::Friction(mu))
        }
        other => Err(format!("{other} is not a contact; {ALLOWED}")),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn contacts_read_and_wrong_ones_say_what_is_allowed() {
        let v = |s: &str| crate::scene::overrides::parse_value(s);
        assert_eq!(parse_contact(&v("\"rough\"")), Ok(WallContact::Rough));
        assert_eq!(parse_contact(&v("\"smooth\"")), Ok(WallContact::Smooth));
        assert_eq!(parse_contact(&v("{ friction = 0.3 }")), Ok(WallContact::Friction(0.3)));
        assert_eq!(parse_contact(&v("{ friction = 0 }")), Ok(WallContact::Friction(0.0)));
        assert!(parse_contact(&v("\"slippery\"")).unwrap_err().contains("allowed: \"rough\", \"smooth\""));
        assert!(parse_contact(&v("{ friction = -0.1 }")).unwrap_err().contains("≥ 0"));
        assert!(parse_contact(&v("{ mu = 0.3 }")).unwrap_err().contains("unknown key `mu`"));
        assert!(parse_contact(&v("0.3")).is_err());
    }
}
