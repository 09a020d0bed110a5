//! The image bits are a contract: every example scene × every kernel renders to the `image_hash`
//! and `ldi_hash` recorded in `tests/data/golden_hashes.tsv`, on the scalar and the SIMD path and
//! for 1 and 3 threads, and every example scene at its own full size renders to its recorded hash.
//!
//! The recorded values were written by the commit before the structure and speed work began
//! (2934191), through the command line, so they do not come from the code they now check. A change
//! that is meant to change an image (a new default) re-records with
//! `CONVSHADOW_RECORD_GOLDEN=1 cargo test --release --test golden_hashes` and says why in its
//! commit.

mod support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

const GOLDEN: &str = "tests/data/golden_hashes.tsv";

/// One render through the CLI: `(image_hash, ldi_hash)` from `--stats-json`.
fn hashes(scene: &Path, extra: &[&str], dir: &Path) -> (String, String) {
    let stats = dir.join("stats.json");
    let mut args = vec![
        "render",
        scene.to_str().unwrap(),
        "-o",
        "out.exr",
        "--quiet",
        "--stats-json",
        stats.to_str().unwrap(),
    ];
    args.extend_from_slice(extra);
    let (code, _, err) = support::run_cli(&args, dir);
    assert_eq!(code, 0, "{} {extra:?}: {err}", scene.display());
    let json: serde_json::Value =
        serde_json::from_str(&std::fs::read_to_string(&stats).unwrap()).unwrap();
    let field = |k: &str| {
        json[k]
            .as_str()
            .unwrap_or_else(|| panic!("{k} in stats"))
            .to_string()
    };
    (field("image_hash"), field("ldi_hash"))
}

/// The example scenes in file-name order; model scenes only where ../shared/models exists.
fn example_scenes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let have_models = support::models_dir().is_some();
    // The MRI scene reads ../shared/volumes, like the model scenes read ../shared/models.
    let have_volumes = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/volumes")
        .is_dir()
        || std::env::var_os("CI").is_some();
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .filter(|p| {
            let text = std::fs::read_to_string(p).unwrap();
            (have_models || !text.contains("shared/models"))
                && (have_volumes || !text.contains("shared/volumes"))
        })
        .collect();
    paths.sort();
    assert!(paths.len() >= 5, "expected the example scenes in scenes/");
    paths
}

fn golden_path() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(GOLDEN)
}

/// `key → (image_hash, ldi_hash)` from the golden file.
fn read_golden() -> BTreeMap<String, (String, String)> {
    let text = std::fs::read_to_string(golden_path()).expect("tests/data/golden_hashes.tsv");
    text.lines()
        .filter(|l| !l.starts_with('#') && !l.trim().is_empty())
        .map(|l| {
            let f: Vec<&str> = l.split('\t').collect();
            assert_eq!(f.len(), 3, "golden line {l:?}");
            (f[0].to_string(), (f[1].to_string(), f[2].to_string()))
        })
        .collect()
}

/// Every case as `(key, scene, CLI arguments)`: the small grid and the full-size scenes.
fn cases() -> Vec<(String, PathBuf, Vec<String>)> {
    let mut out = Vec::new();
    for scene in example_scenes() {
        let name = scene.file_stem().unwrap().to_string_lossy().into_owned();
        for kernel in support::kernels() {
            let args = [
                "--width", "53", "--height", "40", "--slabs", "24", "--kernel", kernel,
            ];
            out.push((
                format!("{name}/{kernel}/53x40x24"),
                scene.clone(),
                args.iter().map(|s| s.to_string()).collect(),
            ));
        }
        out.push((format!("{name}/full"), scene.clone(), Vec::new()));
    }
    out
}

#[test]
fn every_example_scene_and_kernel_keeps_its_recorded_bits() {
    let dir = support::temp_dir("golden");
    let record = std::env::var_os("CONVSHADOW_RECORD_GOLDEN").is_some();
    if record {
        let mut text = String::from(
            "# key\timage_hash\tldi_hash — written by CONVSHADOW_RECORD_GOLDEN=1 (see \
             tests/golden_hashes.rs)\n",
        );
        for (key, scene, args) in cases() {
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let (image, ldi) = hashes(&scene, &args, &dir);
            text += &format!("{key}\t{image}\t{ldi}\n");
        }
        std::fs::write(golden_path(), text).unwrap();
        return;
    }
    let golden = read_golden();
    let mut checked = 0;
    for (key, scene, args) in cases() {
        let want = golden
            .get(&key)
            .unwrap_or_else(|| panic!("{key} is not in {GOLDEN}"));
        let base: Vec<&str> = args.iter().map(String::as_str).collect();
        // The full-size scenes once on the default path; the small grid on both paths and
        // thread counts.
        let variants: &[&[&str]] = if key.ends_with("/full") {
            &[&[]]
        } else {
            &[
                &["--path", "scalar", "--threads", "1"],
                &["--path", "simd", "--threads", "3"],
            ]
        };
        for variant in variants {
            let all: Vec<&str> = base.iter().chain(variant.iter()).copied().collect();
            let got = hashes(&scene, &all, &dir);
            assert_eq!(
                &got, want,
                "{key} {variant:?}: (image_hash, ldi_hash) changed"
            );
            checked += 1;
        }
    }
    assert!(checked > 100, "only {checked} cases checked");
}

#[test]
fn the_golden_check_can_fail() {
    // Guards the guard: another seed is another image, so a changed image cannot pass.
    let dir = support::temp_dir("golden-fail");
    let golden = read_golden();
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/default.toml");
    let args = [
        "--width", "53", "--height", "40", "--slabs", "24", "--kernel", "ellipse2", "--seed", "7",
    ];
    let got = hashes(&scene, &args, &dir);
    assert_ne!(got.0, golden["default/ellipse2/53x40x24"].0);
}
