//! Guards for the bit-exactness rules that are properties of the source code: no fused
//! multiply-add anywhere, no libm transcendentals in per-pixel stages (their tables are built
//! once on the host), and randomness only from the integer hash. (Thread-count independence is
//! tested in determinism.rs.)
//!
//! Each rule is a function over (file, text) returning its violations, so that the tests below
//! show every rule failing on an injected violating line, in Rust and in WGSL, and passing on the
//! real tree. The per-pixel scope is by folder (`cpu/src`, `common/src`, `gpu/src`: whatever
//! files they hold), less an explicit allow-list of host-side code.

use std::path::{Path, PathBuf};

/// One violation: file, 1-based line, the code on it.
#[derive(Debug)]
#[allow(dead_code)] // The fields are read through `Debug`, in the failure messages.
struct Hit {
    file: PathBuf,
    line: usize,
    code: String,
}

/// A rule: the violations of one file's text (none when the rule does not cover the file).
type Rule = fn(&Path, &str) -> Vec<Hit>;

/// Host-side code inside the per-pixel folders, which may call transcendentals: (path relative
/// to the repository, prefix-matched; why).
const HOST_SIDE: [(&str, &str); 7] = [
    (
        "common/src/tonemap.rs",
        "display mapping of the finished image for PNG output",
    ),
    (
        "common/src/kernel",
        "tap tables: built once per light on the host in f64",
    ),
    (
        "common/src/plan.rs",
        "per-light and per-material tables of the plan",
    ),
    ("common/src/mesh", "host geometry: procedural shapes"),
    (
        "common/src/image_io.rs",
        "sRGB encoding of the finished image",
    ),
    (
        "common/src/metrics.rs",
        "image comparison (`convshadow diff`)",
    ),
    (
        "cpu/src/reference",
        "the f64 ground-truth references, not a sweep stage",
    ),
];

/// Rust and WGSL files under `dir`, recursively (build outputs and hidden folders skipped).
fn sources(dir: &Path, out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() {
            if !name.starts_with('.') && name != "target" && !name.starts_with("target-") {
                sources(&p, out);
            }
        } else if name.ends_with(".rs") || name.ends_with(".wgsl") {
            out.push(p);
        }
    }
}

/// The repository root.
fn root() -> &'static Path {
    Path::new(env!("CARGO_MANIFEST_DIR"))
}

/// Every Rust and WGSL file of the repository, as paths relative to its root.
fn all_files() -> Vec<PathBuf> {
    let mut files = Vec::new();
    for d in ["common", "cpu", "gpu", "src", "benches", "tests", "fuzz"] {
        sources(&root().join(d), &mut files);
    }
    files
        .into_iter()
        .map(|f| f.strip_prefix(root()).unwrap().to_path_buf())
        .collect()
}

/// Code lines of a file: comments stripped, and, in Rust, nothing from a `#[cfg(test)]`
/// module on (unit tests compute expected values in f64). 1-based line numbers.
fn code_lines(file: &Path, text: &str) -> Vec<(usize, String)> {
    let rust = file.extension().is_some_and(|e| e == "rs");
    let mut out = Vec::new();
    let mut lines = text.lines().enumerate().peekable();
    while let Some((i, l)) = lines.next() {
        if rust
            && l.trim() == "#[cfg(test)]"
            && lines
                .peek()
                .is_some_and(|(_, n)| n.trim_start().starts_with("mod tests"))
        {
            break;
        }
        let code = l.split("//").next().unwrap_or("");
        if !code.trim().is_empty() {
            out.push((i + 1, code.to_string()));
        }
    }
    out
}

/// The hits of a line predicate over a file's code lines.
fn hits(file: &Path, text: &str, bad: impl Fn(&str) -> bool) -> Vec<Hit> {
    code_lines(file, text)
        .into_iter()
        .filter(|(_, c)| bad(c))
        .map(|(line, code)| Hit {
            file: file.to_path_buf(),
            line,
            code,
        })
        .collect()
}

/// Whether `line` calls `name` as a function or method: `name(`, `.name(`, `::name(` (spaces
/// before the parenthesis allowed), not a longer identifier and not its definition.
fn calls(line: &str, name: &str) -> bool {
    let ident = |c: char| c.is_ascii_alphanumeric() || c == '_';
    let mut from = 0;
    while let Some(at) = line[from..].find(name) {
        let start = from + at;
        let end = start + name.len();
        from = end;
        if line[..start].chars().next_back().is_some_and(ident) {
            continue;
        }
        if !line[end..].trim_start().starts_with('(') {
            continue;
        }
        if line[..start].trim_end().ends_with("fn") {
            continue;
        }
        return true;
    }
    false
}

/// Rule: no fused multiply-add, anywhere (Rust `mul_add`, WGSL and C `fma`).
fn no_fused_multiply_add(file: &Path, text: &str) -> Vec<Hit> {
    // The names are assembled so that this file does not match its own search.
    let names = [
        concat!("mul", "_add"),
        concat!("fm", "a"),
        concat!("fm", "af"),
    ];
    hits(file, text, |c| names.iter().any(|n| calls(c, n)))
}

/// The transcendental functions and methods of Rust's `f32`/`f64` and of WGSL.
const TRANSCENDENTALS: [&str; 24] = [
    "sin", "cos", "tan", "asin", "acos", "atan", "atan2", "sinh", "cosh", "tanh", "sin_cos", "exp",
    "exp2", "exp_m1", "ln", "ln_1p", "log", "log2", "log10", "pow", "powf", "powi", "cbrt",
    "hypot",
];

/// Whether a file is per-pixel code: under `cpu/src`, `common/src` or `gpu/src`, not host-side.
fn is_per_pixel(file: &Path) -> bool {
    let path = file.to_string_lossy().replace('\\', "/");
    let in_scope = ["cpu/src/", "common/src/", "gpu/src/"]
        .iter()
        .any(|d| path.starts_with(d));
    let unit_tests = file.file_name().is_some_and(|n| n == "tests.rs");
    in_scope && !unit_tests && !HOST_SIDE.iter().any(|(p, _)| path.starts_with(p))
}

/// Rule: per-pixel stages call no transcendental (they read tables built on the host).
fn no_transcendentals_per_pixel(file: &Path, text: &str) -> Vec<Hit> {
    if !is_per_pixel(file) {
        return Vec::new();
    }
    hits(file, text, |c| TRANSCENDENTALS.iter().any(|n| calls(c, n)))
}

/// Rule: randomness only from the integer hash (no `rand`, no clock seeds) outside the tests.
fn randomness_only_from_the_hash(file: &Path, text: &str) -> Vec<Hit> {
    if file.starts_with("tests") {
        return Vec::new();
    }
    hits(file, text, |c| {
        c.contains("rand::") || c.contains("thread_rng") || c.contains("SystemTime")
    })
}

/// The violations of `rule` over the whole tree.
fn tree_hits(rule: Rule) -> Vec<Hit> {
    all_files()
        .into_iter()
        .flat_map(|f| {
            let text = std::fs::read_to_string(root().join(&f)).unwrap();
            rule(&f, &text)
        })
        .collect()
}

/// The scan really covers the per-pixel folders, including the files a fixed list once missed.
#[test]
fn the_per_pixel_scope_covers_every_stage_file() {
    let files = all_files();
    let per_pixel: Vec<&PathBuf> = files.iter().filter(|f| is_per_pixel(f)).collect();
    for must in [
        "common/src/hash.rs",
        "common/src/noise.rs",
        "cpu/src/ldi.rs",
    ] {
        assert!(
            per_pixel.iter().any(|f| f.as_path() == Path::new(must)),
            "{must} is not scanned: {per_pixel:?}"
        );
    }
    let wgsl = per_pixel
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "wgsl"));
    assert!(
        wgsl.count() >= 5,
        "the WGSL stages are not scanned: {per_pixel:?}"
    );
    for (prefix, _) in HOST_SIDE {
        assert!(
            files.iter().any(|f| f.starts_with(prefix)),
            "allow-list entry {prefix} matches no file"
        );
    }
}

#[test]
fn no_fused_multiply_add_anywhere() {
    let hits = tree_hits(no_fused_multiply_add);
    assert!(
        hits.is_empty(),
        "fused multiply-add breaks bit-exactness: {hits:?}"
    );
}

#[test]
fn per_pixel_stages_call_no_transcendentals() {
    let hits = tree_hits(no_transcendentals_per_pixel);
    assert!(
        hits.is_empty(),
        "transcendentals belong in per-light tables: {hits:?}"
    );
}

#[test]
fn randomness_comes_only_from_the_hash() {
    let hits = tree_hits(randomness_only_from_the_hash);
    assert!(hits.is_empty(), "{hits:?}");
}

/// `rule` finds `line` injected into `file` (between two clean lines), and not once commented out.
fn catches(rule: Rule, file: &str, line: &str) -> bool {
    let file = Path::new(file);
    let text = format!("fn clean() {{}}\n{line}\nfn also_clean() {{}}\n");
    let found = rule(file, &text);
    let commented = rule(file, &format!("// {line}\n"));
    assert!(commented.is_empty(), "{line:?} commented out still matches");
    found.len() == 1 && found[0].line == 2
}

#[test]
fn the_fused_multiply_add_rule_fails_on_an_injected_violation() {
    let rule: Rule = no_fused_multiply_add;
    assert!(catches(
        rule,
        "cpu/src/sweep.rs",
        &format!("let y = a.{}(b, c);", concat!("mul", "_add"))
    ));
    assert!(catches(
        rule,
        "common/src/plan.rs",
        &format!("let y = f64::{}(a, b, c);", concat!("mul", "_add"))
    ));
    assert!(catches(
        rule,
        "gpu/src/shaders/sweep.wgsl",
        &format!("let y = {}(a, b, c);", concat!("fm", "a"))
    ));
    assert!(catches(
        rule,
        "gpu/src/shaders/sweep.wgsl",
        &format!("let y = {} (a, b, c);", concat!("fm", "a"))
    ));
    assert!(!catches(rule, "cpu/src/sweep.rs", "let y = a * b + c;"));
    assert!(!catches(rule, "cpu/src/sweep.rs", "let y = formula(a);"));
}

#[test]
fn the_transcendental_rule_fails_on_an_injected_violation() {
    let rule: Rule = no_transcendentals_per_pixel;
    assert!(catches(rule, "cpu/src/sweep_simd.rs", "let y = x.sin();"));
    assert!(catches(
        rule,
        "cpu/src/lane/shading.rs",
        "let y = f32::exp(x);"
    ));
    assert!(catches(rule, "common/src/hash.rs", "let y = x.powf(2.2);"));
    assert!(catches(
        rule,
        "common/src/lane.rs",
        "let (s, c) = x.sin_cos();"
    ));
    assert!(catches(
        rule,
        "gpu/src/shaders/shading.wgsl",
        "let y = sin(x);"
    ));
    assert!(catches(
        rule,
        "gpu/src/shaders/sweep.wgsl",
        "let y = exp2 (x) * pow(a, b);"
    ));
    // Not calls, or not per-pixel code.
    assert!(!catches(
        rule,
        "gpu/src/shaders/sweep.wgsl",
        "let cosine = sinus + x;"
    ));
    assert!(!catches(rule, "cpu/src/sweep.rs", "fn log(x: f32) {}"));
    assert!(!catches(
        rule,
        "common/src/kernel/table.rs",
        "let y = x.sin();"
    ));
    assert!(!catches(rule, "common/src/plan.rs", "let y = x.powf(2.2);"));
    // A unit-test module at the end of a per-pixel file may compute expected values.
    let text = "fn f() {}\n#[cfg(test)]\nmod tests {\n    let y = x.sin();\n}\n";
    assert!(rule(Path::new("cpu/src/kernels.rs"), text).is_empty());
}

#[test]
fn the_randomness_rule_fails_on_an_injected_violation() {
    let rule: Rule = randomness_only_from_the_hash;
    assert!(catches(
        rule,
        "cpu/src/kernels.rs",
        "let r = rand::random::<u32>();"
    ));
    assert!(catches(
        rule,
        "src/report/runner.rs",
        "let mut g = thread_rng();"
    ));
    assert!(catches(
        rule,
        "common/src/hash.rs",
        "let s = SystemTime::now();"
    ));
    // WGSL has no library randomness: a clock or rand call there is caught the same way.
    assert!(catches(
        rule,
        "gpu/src/shaders/noise.wgsl",
        "let r = rand::next();"
    ));
    assert!(!catches(
        rule,
        "cpu/src/kernels.rs",
        "let r = mix32(seed ^ x);"
    ));
}
