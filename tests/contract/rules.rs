//! Guards for the bit-exactness rules that are properties of the source code: no fused
//! multiply-add anywhere, no libm transcendentals in per-pixel stages (their tables are built
//! once on the host), and randomness only from the integer hash. (Thread-count independence is
//! tested in determinism.rs.)
//!
//! Each rule is a function over (file, text) returning its violations, so that the tests below
//! show every rule failing on an injected violating line, in Rust and in WGSL, and passing on the
//! real tree. The per-pixel scope is by folder (`common/src/pixel`, `cpu/src`,
//! `gpu/src/shaders`: whatever files they hold), with no allow-list. Beside them: no file-level
//! import circle (`scripts/import_cycles.py`), no Rust file over 900 lines outside tests, and
//! every source path the docs name exists.

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

/// The per-pixel folders: every Rust and WGSL file in them runs per pixel (or per fragment) and
/// keeps the per-pixel rules, with no exception. Host code (the model, preparation, the plan's
/// tables, file formats, the f64 references) lives in other folders.
const PER_PIXEL_FOLDERS: [(&str, &str); 3] = [
    (
        "common/src/pixel/",
        "lanes, hashes, noise and texture evaluation, levels",
    ),
    ("cpu/src/", "the CPU stages and the sweep"),
    ("gpu/src/shaders/", "the WGSL stages"),
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
    for d in [
        "common",
        "io",
        "cpu",
        "reference",
        "gpu",
        "testkit",
        "src",
        "benches",
        "tests",
        "fuzz",
    ] {
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

/// Whether a file is per-pixel code: under one of [`PER_PIXEL_FOLDERS`], not a unit-test file.
fn is_per_pixel(file: &Path) -> bool {
    let path = file.to_string_lossy().replace('\\', "/");
    let unit_tests = file.file_name().is_some_and(|n| n == "tests.rs");
    !unit_tests && PER_PIXEL_FOLDERS.iter().any(|(d, _)| path.starts_with(d))
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
        "common/src/pixel/hash.rs",
        "common/src/pixel/noise.rs",
        "common/src/pixel/lane.rs",
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
    for (folder, _) in PER_PIXEL_FOLDERS {
        assert!(
            per_pixel.iter().any(|f| f.starts_with(folder)),
            "per-pixel folder {folder} holds no file"
        );
    }
    // Host code is outside the scope by where it lives, not by a list.
    for host in [
        "common/src/plan/kernel/table.rs",
        "common/src/model/display.rs",
        "reference/src/shadow_ray.rs",
        "io/src/image.rs",
    ] {
        assert!(
            files.iter().any(|f| f.as_path() == Path::new(host)),
            "{host} missing"
        );
        assert!(!is_per_pixel(Path::new(host)), "{host} is host code");
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
    assert!(catches(
        rule,
        "common/src/pixel/hash.rs",
        "let y = x.powf(2.2);"
    ));
    assert!(catches(
        rule,
        "common/src/pixel/lane.rs",
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
        "common/src/plan/kernel/table.rs",
        "let y = x.sin();"
    ));
    assert!(!catches(
        rule,
        "common/src/plan/mod.rs",
        "let y = x.powf(2.2);"
    ));
    assert!(!catches(rule, "reference/src/edge.rs", "let y = x.exp();"));
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
        "common/src/pixel/hash.rs",
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

/// Whether a Rust file is test code: under `tests/` (any crate's), or a unit-test file.
fn is_test_file(file: &Path) -> bool {
    file.components().any(|c| c.as_os_str() == "tests")
        || file.file_name().is_some_and(|n| n == "tests.rs")
}

/// The Rust files over `limit` lines outside tests.
fn long_files(files: &[PathBuf], limit: usize) -> Vec<(PathBuf, usize)> {
    files
        .iter()
        .filter(|f| f.extension().is_some_and(|e| e == "rs") && !is_test_file(f))
        .filter_map(|f| {
            let lines = std::fs::read_to_string(root().join(f))
                .unwrap()
                .lines()
                .count();
            (lines > limit).then(|| (f.clone(), lines))
        })
        .collect()
}

#[test]
fn no_rust_file_over_900_lines_outside_tests() {
    let long = long_files(&all_files(), 900);
    assert!(long.is_empty(), "split these files: {long:?}");
    // The check sees real files: the largest production file is well over a tenth of the limit.
    assert!(!long_files(&all_files(), 90).is_empty());
    assert!(is_test_file(Path::new("tests/contract/rules.rs")));
    assert!(is_test_file(Path::new("common/src/plan/kernel/tests.rs")));
    assert!(!is_test_file(Path::new("cpu/src/sweep/mod.rs")));
}

/// `scripts/import_cycles.py` over the tree (or over `dir`): its exit status and output.
fn import_cycles(dir: &Path) -> (bool, String) {
    let out = std::process::Command::new("python3")
        .arg(root().join("scripts/import_cycles.py"))
        .arg(dir)
        .output()
        .expect("python3 runs scripts/import_cycles.py");
    let text =
        String::from_utf8_lossy(&out.stdout).into_owned() + &String::from_utf8_lossy(&out.stderr);
    (out.status.success(), text)
}

#[test]
fn no_file_level_import_circle() {
    let (ok, text) = import_cycles(root());
    assert!(ok, "{text}");
    assert!(text.contains("0 import circles"), "{text}");
}

#[test]
fn the_import_circle_script_finds_an_injected_circle() {
    let dir = std::env::temp_dir().join(format!("convshadow-cycles-{}", std::process::id()));
    let src = dir.join("common/src");
    std::fs::create_dir_all(src.join("model")).unwrap();
    std::fs::write(src.join("lib.rs"), "pub mod model;\npub mod plan;\n").unwrap();
    std::fs::write(src.join("model/mod.rs"), "pub mod scene;\n").unwrap();
    // scene -> plan (a grouped `use`), plan -> scene (a path in code): a circle of two files.
    std::fs::write(
        src.join("model/scene.rs"),
        "use crate::{plan::Plan, model};\npub struct Scene;\n",
    )
    .unwrap();
    std::fs::write(
        src.join("plan.rs"),
        "pub struct Plan(crate::model::scene::Scene);\n",
    )
    .unwrap();
    let (ok, text) = import_cycles(&dir);
    assert!(!ok, "{text}");
    assert!(text.contains("common/src/model/scene.rs"), "{text}");
    // A comment naming the path is no import: without the code path the circle is gone.
    std::fs::write(
        src.join("plan.rs"),
        "// crate::model::scene::Scene\npub struct Plan;\n",
    )
    .unwrap();
    let (ok, text) = import_cycles(&dir);
    std::fs::remove_dir_all(&dir).unwrap();
    assert!(ok, "{text}");
}

/// The source paths (`…/x.rs`, `…/x.wgsl`, or a bare `x.rs`) a text names, with their lines.
fn named_paths(text: &str) -> Vec<(usize, String)> {
    let mut out = Vec::new();
    for (i, line) in text.lines().enumerate() {
        let chars: Vec<char> = line.chars().collect();
        // `*` belongs to a token, so that a pattern (`gpu/src/*.rs`) stays one and is skipped.
        let is_path_char = |c: char| c.is_ascii_alphanumeric() || "_./-*".contains(c);
        let mut k = 0;
        while k < chars.len() {
            if !is_path_char(chars[k]) {
                k += 1;
                continue;
            }
            let start = k;
            while k < chars.len() && is_path_char(chars[k]) {
                k += 1;
            }
            let token: String = chars[start..k].iter().collect();
            let token = token.trim_end_matches('.');
            let url = start >= 3 && chars[..start].iter().rev().take(3).any(|c| *c == ':');
            if (token.ends_with(".rs") || token.ends_with(".wgsl")) && !url {
                out.push((i + 1, token.to_string()));
            }
        }
    }
    out
}

/// Whether a named path exists: relative to the repository (or, for a name without a folder,
/// as some source file's name; `*` patterns and `NAME` placeholders are not paths).
fn path_exists(named: &str, files: &[PathBuf]) -> bool {
    if named.contains('*') || named.contains("NAME") {
        return true;
    }
    if named.contains('/') {
        let p = named.trim_start_matches("./");
        return root().join(p).exists()
            || files
                .iter()
                .any(|f| f.to_string_lossy().ends_with(&format!("/{p}")));
    }
    files
        .iter()
        .any(|f| f.file_name().is_some_and(|n| n.to_string_lossy() == named))
}

#[test]
fn every_source_path_the_docs_and_comments_name_exists() {
    let files = all_files();
    let mut docs = vec![root().join("README.md")];
    let mut stack = vec![root().join("docs")];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            // The history is a log of past states: its paths were right when written.
            if p.is_dir() && p.file_name().is_some_and(|n| n != "history") {
                stack.push(p);
            } else if p.extension().is_some_and(|x| x == "md") {
                docs.push(p);
            }
        }
    }
    let mut missing = Vec::new();
    for doc in &docs {
        let text = std::fs::read_to_string(doc).unwrap();
        for (line, named) in named_paths(&text) {
            if !path_exists(&named, &files) {
                missing.push(format!("{}:{line}: {named}", doc.display()));
            }
        }
    }
    // Comments in the sources (tests excepted: they inject made-up paths).
    for f in files.iter().filter(|f| !is_test_file(f)) {
        let text = std::fs::read_to_string(root().join(f)).unwrap();
        let comments: String = text
            .lines()
            .map(|l| l.split_once("//").map_or("", |(_, c)| c))
            .collect::<Vec<_>>()
            .join("\n");
        for (line, named) in named_paths(&comments) {
            if !path_exists(&named, &files) {
                missing.push(format!("{}:{line}: {named}", f.display()));
            }
        }
    }
    assert!(missing.is_empty(), "stale paths:\n{}", missing.join("\n"));
    // The scan finds paths at all, and a made-up one is missing.
    assert!(named_paths("see `cpu/src/ldi.rs` and sweep.wgsl.").len() == 2);
    assert_eq!(
        named_paths("`gpu/src/*.rs`"),
        [(1, "gpu/src/*.rs".to_string())]
    );
    assert!(!path_exists("cpu/src/no_such_stage.rs", &files));
    assert!(path_exists("cpu/src/ldi.rs", &files));
}

/// `cargo tree` of one package, every edge kind (dev-dependencies included), offline.
fn dependency_tree(package: &str) -> String {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".to_string());
    let out = std::process::Command::new(cargo)
        .args([
            "tree",
            "--offline",
            "-e",
            "normal,build,dev",
            "--prefix",
            "none",
            "-p",
        ])
        .arg(package)
        .current_dir(root())
        .output()
        .expect("cargo tree runs");
    assert!(
        out.status.success(),
        "cargo tree -p {package}: {}",
        String::from_utf8_lossy(&out.stderr)
    );
    String::from_utf8_lossy(&out.stdout).into_owned()
}

/// The crates of a `cargo tree --prefix none` listing, by name.
fn crate_names(tree: &str) -> Vec<&str> {
    tree.lines()
        .filter_map(|l| l.split_whitespace().next())
        .collect()
}

#[test]
fn the_gpu_port_pulls_no_file_format_and_no_cli_crate() {
    let forbidden = ["nifti", "tobj", "image", "clap", "flate2", "convshadow-io"];
    let gpu = dependency_tree("convshadow-gpu");
    let found: Vec<&str> = crate_names(&gpu)
        .into_iter()
        .filter(|n| forbidden.contains(n))
        .collect();
    assert!(found.is_empty(), "convshadow-gpu depends on {found:?}");
    // The listing is real: the GPU port's own crates are in it, and the file formats are in the
    // root package's tree, where the check would see them.
    assert!(crate_names(&gpu).contains(&"wgpu"));
    let all = dependency_tree("convshadow");
    for name in ["nifti", "tobj", "image", "clap"] {
        assert!(
            crate_names(&all).contains(&name),
            "{name} not in the root's tree"
        );
    }
}
