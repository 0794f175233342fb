//! `soil_contact` of `[container]` and `[[bodies]]`: how soil slides along walls and bodies.
//!
//! ```toml
//! soil_contact = "rough"                 # no slip, adhesive for cohesive soil (the default)
//! soil_contact = "smooth"                # free slip
//! soil_contact = { friction = 0.35 }     # Coulomb: tangential traction ≤ μ × normal
//! ```
//!
//! A container may also set its floor and its four side walls apart (a plane-strain test:
//! smooth side walls on a rough floor); the faces that are not rough share one contact:
//!
//! ```toml
//! soil_contact = { floor = "rough", walls = "smooth" }
//! ```

use regolith_fsi::config::WallContact;

/// How soil slides along the container: its floor and its four side walls.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContainerContact {
    /// The floor (the face at the container's lowest z).
    pub floor: WallContact,
    /// The four side walls.
    pub walls: WallContact,
}

impl ContainerContact {
    /// Every face rough: the default.
    pub const ROUGH: Self = Self { floor: WallContact::Rough, walls: WallContact::Rough };

    /// The same contact on every face.
    pub fn uniform(c: WallContact) -> Self {
        Self { floor: c, walls: c }
    }

    /// True when every face is rough.
    pub fn is_rough(&self) -> bool {
        self.floor == WallContact::Rough && self.walls == WallContact::Rough
    }

    /// The contact the solver gives the walls' markers (owner 0): the one face kind that is not
    /// rough (rough faces get no normal, which keeps their markers rough).
    pub fn owner(&self) -> WallContact {
        if self.floor == WallContact::Rough { self.walls } else { self.floor }
    }
}

/// A contact as a scene writes it.
fn written(c: WallContact) -> String {
    match c {
        WallContact::Rough => "\"rough\"".into(),
        WallContact::Smooth => "\"smooth\"".into(),
        WallContact::Friction(mu) => format!("{{ friction = {mu} }}"),
    }
}

/// Reads a container's `soil_contact`: one contact for every face, or a table of `floor` and
/// `walls`, whose faces that are not rough must share one contact (one coefficient per owner).
pub(super) fn parse_container_contact(v: &toml::Value) -> Result<ContainerContact, String> {
    let toml::Value::Table(t) = v else { return parse_contact(v).map(ContainerContact::uniform) };
    if !t.contains_key("floor") && !t.contains_key("walls") {
        return parse_contact(v).map(ContainerContact::uniform);
    }
    const FACES: &str = "allowed keys: floor, walls (each a contact; an omitted face is rough)";
    if let Some(k) = t.keys().find(|k| *k != "floor" && *k != "walls") {
        return Err(format!("unknown key `{k}` beside floor/walls; {FACES}"));
    }
    let face = |k: &str| t.get(k).map_or(Ok(WallContact::Rough), |f| parse_contact(f).map_err(|m| format!("{k}: {m}")));
    let c = ContainerContact { floor: face("floor")?, walls: face("walls")? };
    if c.floor != WallContact::Rough && c.walls != WallContact::Rough && c.floor != c.walls {
        return Err(format!(
            "floor ({}) and walls ({}) differ and neither is rough; allowed: one of them rough, or both the same",
            written(c.floor),
            written(c.walls)
        ));
    }
    Ok(c)
}

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

    #[test]
    fn a_container_sets_its_floor_and_walls_apart() {
        let v = |s: &str| parse_container_contact(&crate::scene::overrides::parse_value(s));
        assert_eq!(v("\"smooth\""), Ok(ContainerContact::uniform(WallContact::Smooth)));
        assert_eq!(v("{ friction = 0.2 }"), Ok(ContainerContact::uniform(WallContact::Friction(0.2))));
        let c = v("{ floor = \"rough\", walls = \"smooth\" }").expect("per face");
        assert_eq!((c.floor, c.walls, c.owner()), (WallContact::Rough, WallContact::Smooth, WallContact::Smooth));
        let c = v("{ floor = { friction = 0.5 } }").expect("walls omitted");
        assert_eq!((c.walls, c.owner()), (WallContact::Rough, WallContact::Friction(0.5)));
        assert!(v("{ floor = \"smooth\", walls = { friction = 0.3 } }").unwrap_err().contains("neither is rough"));
        assert!(v("{ floor = \"rough\", lid = \"smooth\" }").unwrap_err().contains("unknown key `lid`"));
        assert!(v("{ walls = \"icy\" }").unwrap_err().starts_with("walls: "));
    }
}
