//! The two xacro substitutions a generated URDF may still hold: `$(optenv NAME default…)` and
//! `$(env NAME)`. ROS packages ship URDFs expanded by `xacro` with these left in on purpose
//! (pybullet_data's Husky places its IMU with `$(optenv HUSKY_IMU_XYZ 0.19 0 0.149)`), to be
//! resolved when the robot is loaded. Anything else of xacro's (`$(find …)`, `$(arg …)`,
//! `${…}` expressions, `<xacro:…>` elements) needs the `xacro` tool and is refused here.

/// One substitution resolved in a URDF, for reporting (`regolith check` lists them).
#[derive(Clone, Debug, PartialEq)]
pub struct Substitution {
    /// The substitution as written, `$(optenv HUSKY_IMU_XYZ 0.19 0 0.149)`.
    pub text: String,
    /// Its line in the file (1-based).
    pub line: usize,
    /// The environment variable it reads.
    pub variable: String,
    /// The text it was replaced by.
    pub value: String,
    /// Whether the environment gave the value (else it is `optenv`'s default).
    pub from_env: bool,
}

impl std::fmt::Display for Substitution {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        let from = if self.from_env { "from the environment" } else { "the default" };
        write!(f, "line {}: {} = \"{}\" ({from}, {} ", self.line, self.text, self.value, self.variable)?;
        f.write_str(if self.from_env { "is set)" } else { "is not set)" })
    }
}

const EXPAND: &str = "Regolith resolves only $(optenv NAME default) and $(env NAME); expand the rest first with \
                      the `xacro` tool (`xacro robot.urdf.xacro > robot.urdf`)";

/// Replaces every `$(optenv …)` and `$(env …)` outside comments, reading variables through
/// `env` (as xacro does: the environment's value, else the default — the words after the name,
/// joined by single spaces — and an error for `$(env NAME)` with `NAME` unset). Returns the
/// text and what was replaced; any other xacro construct is an error (`line N: …`).
pub fn substitute(text: &str, env: &dyn Fn(&str) -> Option<String>) -> Result<(String, Vec<Substitution>), String> {
    let mut out = String::with_capacity(text.len());
    let mut used = Vec::new();
    let mut rest = text;
    let mut line = 1;
    while !rest.is_empty() {
        // The next comment or construct of interest, whichever comes first.
        let next = ["<!--", "$(", "${", "<xacro:"]
            .iter()
            .filter_map(|m| rest.find(m).map(|at| (at, *m)))
            .min_by_key(|(at, _)| *at);
        let Some((at, marker)) = next else {
            out.push_str(rest);
            break;
        };
        out.push_str(&rest[..at]);
        line += rest[..at].matches('\n').count();
        rest = &rest[at..];
        match marker {
            "<!--" => {
                let end = rest.find("-->").map_or(rest.len(), |e| e + 3);
                out.push_str(&rest[..end]);
                line += rest[..end].matches('\n').count();
                rest = &rest[end..];
            }
            "${" => {
                let shown: String = rest.chars().take_while(|c| *c != '}' && *c != '"' && *c != '\n').collect();
                return Err(format!("line {line}: `{shown}}}` is a xacro expression; {EXPAND}"));
            }
            "<xacro:" => {
                let name: String =
                    rest[1..].chars().take_while(|c| !c.is_whitespace() && *c != '>' && *c != '/').collect();
                return Err(format!("line {line}: element <{name}> is xacro; {EXPAND}"));
            }
            _ => {
                let Some(close) = rest.find(')') else {
                    return Err(format!("line {line}: `$(` is not closed by `)`; {EXPAND}"));
                };
                let whole = &rest[..=close];
                let inner = &whole[2..close];
                if inner.contains("$(") || inner.contains('\n') {
                    return Err(format!("line {line}: nested or multi-line substitution `{whole}`; {EXPAND}"));
                }
                let words: Vec<&str> = inner.split_whitespace().collect();
                let (value, variable, from_env) = match words.as_slice() {
                    ["optenv", name, default @ ..] => match env(name) {
                        Some(v) => (v, *name, true),
                        None => (default.join(" "), *name, false),
                    },
                    ["env", name] => match env(name) {
                        Some(v) => (v, *name, true),
                        None => {
                            return Err(format!(
                                "line {line}: `{whole}`: environment variable {name} is not set \
                                 ($(env NAME) has no default; set it or write $(optenv {name} default))"
                            ));
                        }
                    },
                    ["optenv"] | ["env", ..] => {
                        return Err(format!(
                            "line {line}: `{whole}`: write $(env NAME) or $(optenv NAME default words)"
                        ));
                    }
                    _ => return Err(format!("line {line}: `{whole}` is a xacro substitution; {EXPAND}")),
                };
                out.push_str(&value);
                used.push(Substitution {
                    text: whole.to_string(),
                    line,
                    variable: variable.to_string(),
                    value,
                    from_env,
                });
                rest = &rest[close + 1..];
            }
        }
    }
    Ok((out, used))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn env(name: &str) -> Option<String> {
        (name == "SET").then(|| "1 2 3".to_string())
    }

    #[test]
    fn optenv_takes_the_environment_else_the_default_words() {
        let (t, used) =
            substitute("<a\nxyz=\"$(optenv UNSET 0.19  0 0.149)\" b=\"$(optenv SET 9)\" c=\"$(env SET)\"/>", &env)
                .expect("resolves");
        assert_eq!(t, "<a\nxyz=\"0.19 0 0.149\" b=\"1 2 3\" c=\"1 2 3\"/>");
        assert_eq!(used.len(), 3);
        assert_eq!((used[0].line, used[0].from_env, used[0].variable.as_str()), (2, false, "UNSET"));
        assert!(used[1].from_env && used[2].from_env);
        assert_eq!(
            used[0].to_string(),
            "line 2: $(optenv UNSET 0.19  0 0.149) = \"0.19 0 0.149\" (the default, UNSET is not set)"
        );
        // No default: the empty string, as xacro gives.
        assert_eq!(substitute("$(optenv UNSET)", &env).expect("empty").0, "");
    }

    #[test]
    fn comments_are_left_alone_and_other_xacro_is_refused() {
        let text = "<!-- $(find x) ${y} <xacro:include/> -->\n<a/>";
        assert_eq!(substitute(text, &env).expect("comment").0, text);
        for (t, want) in [
            ("\n\n<a x=\"$(env UNSET)\"/>", "line 3: `$(env UNSET)`: environment variable UNSET is not set"),
            ("<a x=\"$(find pkg)/m.stl\"/>", "line 1: `$(find pkg)` is a xacro substitution"),
            ("<a x=\"${radius*2}\"/>", "line 1: `${radius*2}` is a xacro expression"),
            ("<!-- c -->\n<xacro:arg name=\"n\"/>", "line 2: element <xacro:arg> is xacro"),
            ("<a x=\"$(optenv A $(env B))\"/>", "nested or multi-line substitution"),
            ("<a x=\"$(env)\"/>", "write $(env NAME)"),
        ] {
            let e = substitute(t, &env).expect_err(t);
            assert!(e.contains(want), "{t}: {e}");
            assert_eq!(e.lines().count(), 1);
        }
    }
}
