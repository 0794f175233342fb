//! The points of a sweep: `--vary key=values` parsed, then crossed (a full grid) or sampled
//! (a Latin hypercube).

use rand::{Rng, SeedableRng, seq::SliceRandom};

use crate::input::InputError;
use crate::scene::overrides::parse_value;

/// What one `--vary` gives a key.
#[derive(Clone, Debug, PartialEq)]
pub enum Values {
    /// Listed values (`key=0,0.1,0.2`; each a TOML value).
    List(Vec<toml::Value>),
    /// A closed interval for a Latin hypercube (`key=lo:hi`, numbers).
    Range(f64, f64),
}

/// One varied key.
#[derive(Clone, Debug, PartialEq)]
pub struct Vary {
    /// Dotted scene key, as `--set` takes it (`rig.slips`, `materials[0].friction_angle`).
    pub key: String,
    /// Its values.
    pub values: Values,
}

/// How the varied keys are combined.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Design {
    /// Every combination of the listed values (the first key varies slowest).
    Grid,
    /// `samples` points, each key's range (or list) cut into `samples` equal strata and every
    /// stratum used once (McKay et al. 1979), from a seeded generator.
    Lhs {
        /// Number of points.
        samples: usize,
        /// Seed of the sampler (the same seed gives the same points).
        seed: u64,
    },
}

/// Parses one `--vary key=values` argument. `key=a,b,c` lists TOML values (commas inside
/// brackets, braces or quotes do not split); `key=lo:hi` is a numeric range.
pub fn parse_vary(arg: &str) -> Result<Vary, InputError> {
    let bad = |m: String| InputError::flag("--vary", m);
    let (key, rest) = arg.split_once('=').ok_or_else(|| bad(format!("`{arg}` is not key=values")))?;
    let key = key.trim();
    if key.is_empty() {
        return Err(bad(format!("`{arg}` has an empty key")));
    }
    let rest = rest.trim();
    if let Some((lo, hi)) = rest.split_once(':')
        && let (Ok(lo), Ok(hi)) = (lo.trim().parse::<f64>(), hi.trim().parse::<f64>())
    {
        if !(lo.is_finite() && hi.is_finite() && lo < hi) {
            return Err(bad(format!("{key}: a range lo:hi needs finite lo < hi (got {rest})")));
        }
        return Ok(Vary { key: key.to_string(), values: Values::Range(lo, hi) });
    }
    let items = split_top_level(rest);
    if items.iter().any(|s| s.trim().is_empty()) {
        return Err(bad(format!("{key}: empty value in `{rest}` (allowed: a,b,c or lo:hi)")));
    }
    let values: Vec<toml::Value> = items.iter().map(|s| parse_value(s.trim())).collect();
    // A repeated value makes two points of one configuration: one id, one output folder.
    for (i, v) in values.iter().enumerate() {
        if values[..i].contains(v) {
            return Err(bad(format!("{key}: value {v} is listed twice (each point must differ)")));
        }
    }
    Ok(Vary { key: key.to_string(), values: Values::List(values) })
}

/// Splits on commas that are not inside `[]`, `{}` or quotes.
fn split_top_level(s: &str) -> Vec<String> {
    let (mut out, mut cur, mut depth, mut quote) = (Vec::new(), String::new(), 0i32, None::<char>);
    for c in s.chars() {
        match (quote, c) {
            (Some(q), c) if c == q => quote = None,
            (Some(_), _) => {}
            (None, '"' | '\'') => quote = Some(c),
            (None, '[' | '{') => depth += 1,
            (None, ']' | '}') => depth -= 1,
            (None, ',') if depth == 0 => {
                out.push(std::mem::take(&mut cur));
                continue;
            }
            _ => {}
        }
        cur.push(c);
    }
    out.push(cur);
    out
}

/// The override sets of a design, in point order.
pub fn points(vary: &[Vary], design: Design) -> Result<Vec<Vec<(String, toml::Value)>>, InputError> {
    if vary.is_empty() {
        return Err(InputError::flag("--vary", "a sweep needs at least one --vary key=values".to_string()));
    }
    let mut seen = std::collections::HashSet::new();
    for v in vary {
        if !seen.insert(v.key.as_str()) {
            return Err(InputError::flag("--vary", format!("{} is varied twice", v.key)));
        }
    }
    match design {
        Design::Grid => {
            let lists = vary
                .iter()
                .map(|v| match &v.values {
                    Values::List(l) => Ok(l.as_slice()),
                    Values::Range(..) => Err(InputError::flag(
                        "--vary",
                        format!("{}: a grid needs listed values (a,b,c); lo:hi ranges are for --design lhs", v.key),
                    )),
                })
                .collect::<Result<Vec<_>, _>>()?;
            let total: usize = lists.iter().map(|l| l.len()).product();
            Ok((0..total)
                .map(|mut n| {
                    let mut idx = vec![0; lists.len()];
                    for k in (0..lists.len()).rev() {
                        idx[k] = n % lists[k].len();
                        n /= lists[k].len();
                    }
                    vary.iter().zip(&lists).zip(idx).map(|((v, l), i)| (v.key.clone(), l[i].clone())).collect()
                })
                .collect())
        }
        Design::Lhs { samples, seed } => {
            if samples == 0 {
                return Err(InputError::flag("--samples", "must be at least 1 for --design lhs".to_string()));
            }
            let mut rng = rand_chacha::ChaCha8Rng::seed_from_u64(seed);
            let columns: Vec<Vec<toml::Value>> = vary
                .iter()
                .map(|v| {
                    let mut strata: Vec<usize> = (0..samples).collect();
                    strata.shuffle(&mut rng);
                    strata
                        .into_iter()
                        .map(|s| {
                            let u = (s as f64 + rng.random::<f64>()) / samples as f64;
                            match &v.values {
                                Values::Range(lo, hi) => toml::Value::Float(lo + u * (hi - lo)),
                                Values::List(l) => l[((u * l.len() as f64) as usize).min(l.len() - 1)].clone(),
                            }
                        })
                        .collect()
                })
                .collect();
            Ok((0..samples)
                .map(|i| vary.iter().zip(&columns).map(|(v, c)| (v.key.clone(), c[i].clone())).collect())
                .collect())
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lists_split_at_top_level_commas_only() {
        let v = parse_vary("rig.slips=[0.1, 0.2],[0.3]").expect("parse");
        assert_eq!(v.values, Values::List(vec![parse_value("[0.1, 0.2]"), parse_value("[0.3]")]));
        let v = parse_vary("simulation.backend=cpu,\"wgpu\"").expect("parse");
        assert_eq!(v.values, Values::List(vec![toml::Value::from("cpu"), toml::Value::from("wgpu")]));
        assert_eq!(parse_vary("a=1:2").expect("range").values, Values::Range(1.0, 2.0));
        assert!(parse_vary("a=2:1").is_err());
        assert!(parse_vary("a=1,,2").is_err());
        assert!(parse_vary("=1").is_err());
        let e = parse_vary("a=0.2,0.4,0.2").expect_err("repeated value").to_string();
        assert!(e.contains("value 0.2 is listed twice"), "{e}");
    }

    #[test]
    fn grid_crosses_and_lhs_fills_every_stratum_once() {
        let a = parse_vary("a=1,2,3").expect("a");
        let b = parse_vary("b=10,20").expect("b");
        let g = points(&[a.clone(), b.clone()], Design::Grid).expect("grid");
        assert_eq!(g.len(), 6);
        assert_eq!(g[1], vec![("a".to_string(), toml::Value::Integer(1)), ("b".to_string(), toml::Value::Integer(20))]);
        assert!(points(&[a.clone(), a.clone()], Design::Grid).is_err(), "a key varied twice");
        let r = parse_vary("r=0:1").expect("r");
        assert!(points(std::slice::from_ref(&r), Design::Grid).is_err(), "a range in a grid");
        let n = 8;
        let l = points(&[r.clone(), a], Design::Lhs { samples: n, seed: 7 }).expect("lhs");
        let mut strata: Vec<usize> =
            l.iter().map(|p| (p[0].1.as_float().expect("float") * n as f64) as usize).collect();
        strata.sort_unstable();
        assert_eq!(strata, (0..n).collect::<Vec<_>>(), "each eighth of [0, 1] holds one point");
        assert_eq!(
            l,
            points(&[r, parse_vary("a=1,2,3").expect("a")], Design::Lhs { samples: n, seed: 7 }).expect("again")
        );
    }
}
