//! Guards for the bit-exactness rules of DESIGN §3 that are properties of the source code:
//! no fused multiply-add anywhere, no libm transcendentals in per-pixel stages, and randomness
//! only from the integer hash. (Thread-count independence is tested in determinism.rs.)

use std::path::{Path, PathBuf};

fn sources(dir: &Path, exts: &[&str], out: &mut Vec<PathBuf>) {
    let Ok(entries) = std::fs::read_dir(dir) else {
        return;
    };
    for e in entries {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_string_lossy().into_owned();
        if p.is_dir() {
            if !name.starts_with('.')
                && name != "target"
                && !name.starts_with("target-")
                && name != "fuzz"
            {
                sources(&p, exts, out);
            }
        } else if exts.iter().any(|x| name.ends_with(x)) {
            out.push(p);
        }
    }
}

/// Code lines (comments stripped) of every Rust and WGSL file in the repository.
fn code_lines() -> Vec<(PathBuf, usize, String)> {
    let root = Path::new(env!("CARGO_MANIFEST_DIR"));
    let mut files = Vec::new();
    for d in ["common", "cpu", "gpu", "src", "benches"] {
        sources(&root.join(d), &[".rs", ".wgsl"], &mut files);
    }
    let mut lines = Vec::new();
    for f in files {
        for (i, l) in std::fs::read_to_string(&f).unwrap().lines().enumerate() {
            let code = l.split("//").next().unwrap_or("").to_string();
            lines.push((f.clone(), i + 1, code));
        }
    }
    lines
}

#[test]
fn no_fused_multiply_add_anywhere() {
    let hits: Vec<_> = code_lines()
        .into_iter()
        // The patterns are assembled so that this file does not match its own search.
        .filter(|(_, _, c)| {
            c.contains(concat!("mul", "_add"))
                || c.contains(concat!("fma", "("))
                || c.contains(concat!("fm", "af"))
        })
        .collect();
    assert!(
        hits.is_empty(),
        "fused multiply-add breaks bit-exactness: {hits:?}"
    );
}

#[test]
fn per_pixel_stages_call_no_transcendentals() {
    let per_pixel = [
        "kernels.rs",
        "shading.rs",
        "composite.rs",
        "sweep.rs",
        "parity.rs",
        "noise.rs",
        "texture3d.rs",
    ];
    let banned = [
        ".sin(",
        ".cos(",
        ".tan(",
        ".exp(",
        ".ln(",
        ".log",
        ".powf(",
        ".powi(",
        ".atan",
        ".sin_cos(",
        ".cbrt(",
    ];
    let hits: Vec<_> = code_lines()
        .into_iter()
        .filter(|(f, _, c)| {
            let name = f.file_name().unwrap().to_string_lossy();
            per_pixel.iter().any(|p| name == *p) && banned.iter().any(|b| c.contains(b))
        })
        .filter(|(_, _, c)| !c.contains("#[test]"))
        .collect();
    // Test modules inside these files may use f64 maths for expected values; they live after
    // `mod tests`, so only lines before it count.
    let hits: Vec<_> = hits
        .into_iter()
        .filter(|(f, line, _)| {
            let text = std::fs::read_to_string(f).unwrap();
            let test_start = text
                .lines()
                .position(|l| l.contains("mod tests"))
                .map_or(usize::MAX, |i| i + 1);
            *line < test_start
        })
        .collect();
    assert!(
        hits.is_empty(),
        "transcendentals belong in per-light tables: {hits:?}"
    );
}

#[test]
fn randomness_comes_only_from_the_hash() {
    let hits: Vec<_> = code_lines()
        .into_iter()
        .filter(|(_, _, c)| {
            c.contains("rand::") || c.contains("thread_rng") || c.contains("SystemTime")
        })
        .collect();
    assert!(hits.is_empty(), "{hits:?}");
}
