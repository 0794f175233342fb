//! The one neighbour loop of the WGSL kernels.
//!
//! WGSL has neither closures nor generics over storage buffers, so a loop over the records near
//! a point cannot be a function. A kernel writes it as
//!
//! ```text
//! for_each_in_reach(j, start, rc) {
//!     // body: j is the index of a record of the cell-sorted array whose cell starts are `start`
//! }
//! ```
//!
//! and [`expand`] turns each such statement into WGSL before compilation: the columns of the
//! reach `rc` (a `Reach` of common.wgsl) in x then y, each a contiguous z range of records. That
//! is the CPU's visiting order (`regolith_fsi::cpu::neighbors`), so the sums of both backends
//! add the same terms in the same order. The loop is written here only; the text of the kernels
//! keeps its lines (the expansion of a header or of its closing brace stays on that line), so a
//! compiler message still points at the kernel's own line.

/// The statement's name as a kernel writes it, with its opening parenthesis.
const NAME: &str = "for_each_in_reach(";

/// Why a kernel's source could not be expanded: the line (1-based) and what is wrong there.
#[derive(Debug, Clone, PartialEq, Eq)]
pub(crate) struct ExpandError {
    /// Line of the `for_each_in_reach` statement.
    pub line: usize,
    /// What is wrong with it.
    pub what: String,
}

impl std::fmt::Display for ExpandError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "line {}: for_each_in_reach {}", self.line, self.what)
    }
}

/// `src` with every `for_each_in_reach(index, starts, reach) { body }` replaced by the neighbour
/// loop (nested statements too, each with its own loop variables).
pub(crate) fn expand(src: &str) -> Result<String, ExpandError> {
    let mut s = src.to_owned();
    let mut count = 0usize;
    while let Some(at) = find_statement(&s) {
        let line = s[..at].matches('\n').count() + 1;
        let err = |what: &str| ExpandError { line, what: what.to_owned() };
        let args_from = at + NAME.len();
        let close = s[args_from..].find(')').ok_or_else(|| err("has no closing parenthesis"))? + args_from;
        let args: Vec<&str> = s[args_from..close].split(',').map(str::trim).collect();
        let [index, starts, reach] = args[..] else {
            return Err(err("takes three arguments (index, cell starts, reach)"));
        };
        if let Some(bad) = [index, starts, reach].into_iter().find(|a| !is_identifier(a)) {
            return Err(err(&format!("argument `{bad}` is not an identifier")));
        }
        let after = &s[close + 1..];
        let open = close + 1 + after.len() - after.trim_start().len();
        if !s[open..].starts_with('{') {
            return Err(err("must be followed by `{`"));
        }
        let end = matching_brace(&s, open).ok_or_else(|| err("has no matching `}`"))?;
        let v = |name: &str| format!("nl{count}_{name}");
        let (x, y, lo, hi) = (v("x"), v("y"), v("lo"), v("hi"));
        let header = format!(
            "for (var {x} = {reach}.x0; {x} <= {reach}.x1; {x}++) {{ \
             for (var {y} = {reach}.y0; {y} <= {reach}.y1; {y}++) {{ \
             let {lo} = {starts}[cell_linear({x}, {y}, {reach}.z0)]; \
             let {hi} = {starts}[cell_linear({x}, {y}, {reach}.z1) + 1u]; \
             for (var {index} = {lo}; {index} < {hi}; {index}++) {{"
        );
        // Line breaks between the statement and its brace stay, so later lines keep their numbers.
        let header = header + &"\n".repeat(s[at..open].matches('\n').count());
        // The closing brace first: replacing the header moves everything after it.
        s.replace_range(end..=end, "} } }");
        s.replace_range(at..=open, &header);
        count += 1;
    }
    Ok(s)
}

/// Byte offset of the first `for_each_in_reach(` outside a `//` comment.
fn find_statement(s: &str) -> Option<usize> {
    let mut line_start = 0;
    for line in s.split_inclusive('\n') {
        let code = line.split("//").next().unwrap_or("");
        if let Some(i) = code.find(NAME) {
            let preceded_by_identifier =
                code[..i].chars().next_back().is_some_and(|c| c.is_ascii_alphanumeric() || c == '_');
            if !preceded_by_identifier {
                return Some(line_start + i);
            }
        }
        line_start += line.len();
    }
    None
}

/// Offset of the `}` that closes the `{` at `open`, braces inside `//` comments ignored.
fn matching_brace(s: &str, open: usize) -> Option<usize> {
    let bytes = s.as_bytes();
    let (mut depth, mut i) = (0usize, open);
    while i < bytes.len() {
        match bytes[i] {
            b'/' if bytes.get(i + 1) == Some(&b'/') => {
                i = s[i..].find('\n').map_or(bytes.len(), |n| i + n);
                continue;
            }
            b'{' => depth += 1,
            b'}' => {
                depth -= 1;
                if depth == 0 {
                    return Some(i);
                }
            }
            _ => {}
        }
        i += 1;
    }
    None
}

fn is_identifier(a: &str) -> bool {
    let mut c = a.chars();
    c.next().is_some_and(|f| f.is_ascii_alphabetic() || f == '_')
        && c.all(|x| x.is_ascii_alphanumeric() || x == '_')
        && a != "_"
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Every kernel file the pipelines compile (the same `include_str!` paths).
    const KERNELS: &[(&str, &str)] = &[
        ("active.wgsl", include_str!("kernels/active.wgsl")),
        ("advance.wgsl", include_str!("kernels/advance.wgsl")),
        ("bodies.wgsl", include_str!("kernels/bodies.wgsl")),
        ("classify.wgsl", include_str!("kernels/classify.wgsl")),
        ("common.wgsl", include_str!("kernels/common.wgsl")),
        ("dilate.wgsl", include_str!("kernels/dilate.wgsl")),
        ("dp.wgsl", include_str!("kernels/dp.wgsl")),
        ("extrapolate.wgsl", include_str!("kernels/extrapolate.wgsl")),
        ("forces.wgsl", include_str!("kernels/forces.wgsl")),
        ("materials.wgsl", include_str!("kernels/materials.wgsl")),
        ("mcc.wgsl", include_str!("kernels/mcc.wgsl")),
        ("pack.wgsl", include_str!("kernels/pack.wgsl")),
        ("partition.wgsl", include_str!("kernels/partition.wgsl")),
        ("permute.wgsl", include_str!("kernels/permute.wgsl")),
        ("rates.wgsl", include_str!("kernels/rates.wgsl")),
        ("scan.wgsl", include_str!("kernels/scan.wgsl")),
        ("sort.wgsl", include_str!("kernels/sort.wgsl")),
        ("step_info.wgsl", include_str!("kernels/step_info.wgsl")),
        ("wet.wgsl", include_str!("kernels/wet.wgsl")),
    ];

    #[test]
    fn a_statement_becomes_the_column_loop_in_the_cpus_order_on_the_same_lines() {
        let src = "let rc = reach_of(c);\nfor_each_in_reach(j, start, rc) {\n    if (j == i) { continue; }\n    n++;\n}\nn += 1u;\n";
        let out = expand(src).expect("expands");
        let want = "let rc = reach_of(c);\n\
            for (var nl0_x = rc.x0; nl0_x <= rc.x1; nl0_x++) { \
            for (var nl0_y = rc.y0; nl0_y <= rc.y1; nl0_y++) { \
            let nl0_lo = start[cell_linear(nl0_x, nl0_y, rc.z0)]; \
            let nl0_hi = start[cell_linear(nl0_x, nl0_y, rc.z1) + 1u]; \
            for (var j = nl0_lo; j < nl0_hi; j++) {\n    if (j == i) { continue; }\n    n++;\n} } }\nn += 1u;\n";
        assert_eq!(out, want);
        assert_eq!(out.lines().count(), src.lines().count());
    }

    #[test]
    fn nested_statements_get_their_own_loop_variables_and_comments_are_left_alone() {
        let src = "// for_each_in_reach(q, s, r) { in a comment }\n\
            for_each_in_reach(j, start, rc) { // a brace in a comment: }\n\
            for_each_in_reach(k, m_start, rc) {\n    f(j, k);\n}\n}\n";
        let out = expand(src).expect("expands");
        assert!(out.starts_with("// for_each_in_reach(q, s, r) { in a comment }\n"), "{out}");
        assert_eq!(out.matches("for_each_in_reach").count(), 1, "only the comment keeps it: {out}");
        assert!(out.contains("for (var j = nl0_lo") && out.contains("for (var k = nl1_lo"), "{out}");
        assert!(out.contains("m_start[cell_linear(nl1_x, nl1_y, rc.z0)]"), "{out}");
        let code: String = out.lines().map(|l| l.split("//").next().unwrap_or("")).collect();
        assert_eq!(code.matches('{').count(), code.matches('}').count(), "braces balance: {out}");
        assert_eq!(out.lines().count(), src.lines().count());
        // A brace on the next line: the line count still holds.
        let src = "for_each_in_reach(j, start, rc)\n{\n    n++;\n}\nend;\n";
        let out = expand(src).expect("expands");
        assert_eq!(out.lines().count(), src.lines().count(), "{out}");
        assert!(out.ends_with("    n++;\n} } }\nend;\n"), "{out}");
    }

    #[test]
    fn a_malformed_statement_is_an_error_naming_its_line() {
        let cases = [
            ("x;\nfor_each_in_reach(j, start) {\n}\n", 2, "three arguments"),
            ("for_each_in_reach(j, start, rc.x) {\n}\n", 1, "`rc.x` is not an identifier"),
            ("\n\nfor_each_in_reach(j, start, rc);\n", 3, "followed by `{`"),
            ("for_each_in_reach(j, start, rc) {\n  if (a) {\n}\n", 1, "no matching `}`"),
            ("for_each_in_reach(j, start, rc {\n}\n", 1, "no closing parenthesis"),
        ];
        for (src, line, what) in cases {
            let e = expand(src).expect_err(src);
            assert_eq!(e.line, line, "{e}");
            assert!(e.to_string().contains(what), "{e} (wanted {what:?})");
        }
        // A name that merely ends in the statement's is not one.
        assert_eq!(expand("my_for_each_in_reach(a, b, c);").expect("plain"), "my_for_each_in_reach(a, b, c);");
    }

    /// The loop is written once: no kernel walks the cell columns itself (`cell_linear` over a
    /// reach appears only in the expansion), and every kernel expands.
    #[test]
    fn every_kernel_expands_and_none_writes_the_neighbour_loop_itself() {
        let mut statements = 0;
        for (name, src) in KERNELS {
            let out = expand(src).unwrap_or_else(|e| panic!("{name}: {e}"));
            assert!(find_statement(&out).is_none(), "{name}: a statement left unexpanded");
            for (k, line) in src.lines().enumerate() {
                let code = line.split("//").next().unwrap_or("");
                assert!(
                    !(code.contains("cell_linear(") && code.contains(".z0")),
                    "{name}:{}: a hand-written column loop; use for_each_in_reach",
                    k + 1
                );
            }
            statements += src.lines().filter(|l| l.trim_start().starts_with(NAME)).count();
        }
        // rates (soil, markers), forces, extrapolate and the eight of the wet kernels.
        assert_eq!(statements, 12);
    }
}
