//! `--set key=value` overrides applied to the parsed TOML table before validation.
//!
//! Keys are dotted paths (`simulation.end_time`, `sph.spacing`); array entries are indexed
//! (`materials[0].density`). Values are TOML values (`0.5`, `"f32"`, `[0, 0, -1.62]`); a bare
//! word that is not valid TOML is taken as a string (`--set simulation.backend=cpu`).

/// Parses one `key=value` argument.
pub fn parse_set(arg: &str) -> Result<(String, toml::Value), String> {
    let (k, v) = arg.split_once('=').ok_or_else(|| format!("`{arg}` is not key=value"))?;
    let k = k.trim();
    if k.is_empty() {
        return Err(format!("`{arg}` has an empty key"));
    }
    Ok((k.to_string(), parse_value(v.trim())))
}

/// A value as `--set` and `--vary` take it: TOML (`0.5`, `"f32"`, `[0, 0, -1.62]`), or a bare
/// word that is not valid TOML taken as a string.
pub fn parse_value(v: &str) -> toml::Value {
    match toml::from_str::<toml::Table>(&format!("v = {v}")) {
        Ok(mut t) => t.remove("v").unwrap_or(toml::Value::String(v.to_string())),
        Err(_) => toml::Value::String(v.to_string()),
    }
}

/// The value at a dotted key of a scene table (`rig.slips`, `materials[0].density`), if any.
pub fn get<'a>(table: &'a toml::Table, key: &str) -> Option<&'a toml::Value> {
    let mut cur: Option<&toml::Value> = None;
    for part in key.split('.') {
        let (name, index) = match part.find('[') {
            Some(b) => (&part[..b], part[b + 1..].strip_suffix(']').and_then(|s| s.parse::<usize>().ok())),
            None => (part, None),
        };
        let t = match cur {
            None => table,
            Some(v) => v.as_table()?,
        };
        let v = t.get(name)?;
        cur = Some(match index {
            Some(i) => v.as_array()?.get(i)?,
            None => v,
        });
    }
    cur
}

/// Sets `key` in `table`, creating intermediate tables as needed.
pub(crate) fn apply(table: &mut toml::Table, key: &str, value: toml::Value) -> Result<(), String> {
    let parts: Vec<&str> = key.split('.').collect();
    let mut cur = table;
    for (n, part) in parts.iter().enumerate() {
        let last = n + 1 == parts.len();
        let (name, index) = match part.find('[') {
            Some(b) => {
                let idx = part[b + 1..]
                    .strip_suffix(']')
                    .and_then(|s| s.parse::<usize>().ok())
                    .ok_or_else(|| format!("bad index in `{part}`"))?;
                (&part[..b], Some(idx))
            }
            None => (*part, None),
        };
        if name.is_empty() {
            return Err(format!("empty key segment in `{key}`"));
        }
        match index {
            Some(i) => {
                let arr = cur
                    .get_mut(name)
                    .and_then(|v| v.as_array_mut())
                    .ok_or_else(|| format!("`{name}` is not an array in the scene"))?;
                let len = arr.len();
                let entry =
                    arr.get_mut(i).ok_or_else(|| format!("`{name}` has {len} entries; index {i} is out of range"))?;
                if last {
                    *entry = value;
                    return Ok(());
                }
                cur = entry.as_table_mut().ok_or_else(|| format!("`{name}[{i}]` is not a table"))?;
            }
            None => {
                if last {
                    cur.insert(name.to_string(), value);
                    return Ok(());
                }
                let next = cur.entry(name.to_string()).or_insert_with(|| toml::Value::Table(toml::Table::new()));
                cur = next.as_table_mut().ok_or_else(|| format!("`{name}` is not a table"))?;
            }
        }
    }
    Ok(())
}

/// `regolith run SCENE --set KEY=VALUE ...`: the command that reproduces one run of a scene
/// with overrides, each word quoted for a POSIX shell where it needs it.
pub fn command_line(scene: &std::path::Path, overrides: &[(String, toml::Value)]) -> String {
    let mut c = format!("regolith run {}", shell_word(&scene.display().to_string()));
    for (k, v) in overrides {
        let v = match v {
            toml::Value::String(s) => s.clone(),
            v => v.to_string(),
        };
        c.push_str(&format!(" --set {}", shell_word(&format!("{k}={v}"))));
    }
    c
}

fn shell_word(s: &str) -> String {
    if s.chars().all(|c| c.is_ascii_alphanumeric() || "._-/=+,".contains(c)) {
        s.to_string()
    } else {
        format!("'{}'", s.replace('\'', r"'\''"))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn sets_nested_and_indexed_keys() {
        let mut t: toml::Table =
            toml::from_str("[simulation]\nend_time = 1.0\n[[materials]]\nname = \"a\"\n").expect("toml");
        let (k, v) = parse_set("simulation.end_time=0.5").expect("parse");
        apply(&mut t, &k, v).expect("apply");
        let (k, v) = parse_set("materials[0].density=1700").expect("parse");
        apply(&mut t, &k, v).expect("apply");
        let (k, v) = parse_set("simulation.backend=cpu").expect("parse");
        apply(&mut t, &k, v).expect("apply");
        assert_eq!(t["simulation"]["end_time"].as_float(), Some(0.5));
        assert_eq!(t["materials"][0]["density"].as_integer(), Some(1700));
        assert_eq!(t["simulation"]["backend"].as_str(), Some("cpu"));
        assert!(apply(&mut t, "materials[3].density", toml::Value::Integer(1)).is_err());
        assert!(parse_set("nokey").is_err());
    }
}
