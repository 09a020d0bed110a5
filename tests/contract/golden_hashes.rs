//! The image bits are a contract: every example scene × every kernel renders to the `image_hash`
//! and `ldi_hash` recorded for it, on the scalar and the SIMD path and for 1 and 3 threads, and
//! every example scene at its own full size renders to its recorded hash. Three tables:
//!
//! - `tests/data/golden_hashes_band0.tsv`: the bits of commit 2934191, before the structure, speed
//!   and guard-band work, written through the command line by that commit (so they do not come
//!   from the code they now check), checked with `--guard-band 0 --penumbra iterated` (the
//!   defaults then). Never re-recorded: the sweep's rewrites for speed must keep these bits.
//!   Scenes added later (`shaft`, `gobo`, `narrowband`, `floor`, `cloud_vdb`) are not in it. The rows of a
//!   scene whose own file changed pin that file, not the code: when issue 40 re-lit `bunny`,
//!   `armadillo`, `spot` and `mri` for the gallery (a smaller key light, the wall closer), their
//!   rows here and in the next table were rendered anew with the table's flags. Checked with
//!   `--surface flat` since lambert surfaces became the default (2026-12-04), like the next, and
//!   `--media first-order` since second-order media did (2026-12-05, issue 46), and
//!   `--horizon false` since the horizon did (2026-12-07, issue 46), and `--served-releases false`
//!   since served releases did (2026-12-08, issue 40).
//! - `tests/data/golden_hashes_iterated.tsv`: the same cases with the automatic guard band and the
//!   iterated penumbra, recorded when the guard band became the default (new scenes added with
//!   their rows). Never re-recorded either — but for the rows of the scenes with held surfaces,
//!   all recorded after the surface hold existed (backlit, floor, rimlit, sunlit, teapot), when a
//!   hold began to end at a crossing with something behind it (2026-12-07, docs/how-it-works.md
//!   "Where a hold ends early"), and again for backlit, rimlit and the full-size floor and
//!   sunlit when lit exit faces got their exit hold (same day, "The exit hold"), and for the
//!   teapot (the one scene with an open mesh) when thin shells got their barrier (same day,
//!   "The barrier behind a thin shell"), and for backlit, floor, rimlit and sunlit when a
//!   crossing that leaves a closed mesh stopped starting a hold (same day, "Leaving a mesh
//!   starts no hold"), rendered anew by the CLI at `--path scalar --threads 1`; no other row
//!   changed. Checked with `--penumbra iterated --surface flat --media first-order
//!   --subpixel-shadows false --horizon false --served-releases false`.
//! - `tests/data/golden_hashes.tsv`: the same cases with the defaults (automatic guard band,
//!   distance penumbra), recorded when the distance penumbra became the default and re-recorded
//!   when lambert surfaces did (2026-12-04, issue 40: opaque surfaces get max(0, n·l)) and when
//!   second-order media did (2026-12-05, issue 46: a medium's slabs count the part inside it,
//!   let through its exact transmittance and light the shading point), and for the scenes with
//!   held surfaces when a hold began to end at a crossing with something behind it (2026-12-07,
//!   issues 40/41: a thin plate's shadow was lost behind a 1023-slab hold) and when lit exit
//!   faces got their exit hold (same day: a floor lit towards the viewer came out in black
//!   rows at small image sizes), and for the teapot when thin shells got their barrier (same
//!   day: a turned opaque shell let light through, the teapot's shadow grey), and for backlit,
//!   cloud_vdb, floor, rimlit and sunlit when leaving a closed mesh stopped starting a hold
//!   (same day: its release darkened a soft point light's penumbra far behind), and when the
//!   horizon became the default (same day, issue 46: at an opaque crossing the light below the
//!   tangent plane is blocked; every scene with an opaque surface oblique to the view changed),
//!   and for backlit, floor, rimlit, sunlit and teapot when released light began to be served
//!   on its own surface (2026-12-08, issue 40: a steep receiver's released pixels no longer
//!   darken and deepen the penumbra of another occluder's shadow on it).
//!   A change that is
//!   meant to change an image (a new default) re-records this table with
//!   `CONVSHADOW_RECORD_GOLDEN=1 cargo test --release --test contract golden_hashes::` and says
//!   why in its commit.

use crate::support;

use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

/// The defaults' table (also read by `determinism.rs`).
pub(crate) const GOLDEN: &str = "tests/data/golden_hashes.tsv";
/// The pre-guard-band bits, checked with `--guard-band 0 --penumbra iterated`.
const GOLDEN_BAND0: &str = "tests/data/golden_hashes_band0.tsv";
/// The iterated penumbra's bits with the automatic guard band, checked with `--penumbra iterated`.
const GOLDEN_ITERATED: &str = "tests/data/golden_hashes_iterated.tsv";
/// The model the two earlier tables were recorded with: the iterated penumbra, flat surfaces, the
/// paper's first-order media, shadows carried in whole pixels (sub-pixel shadows, which the
/// iterated penumbra has had since 2026-12-05, change the all-opaque scenes) and no horizon
/// (since 2026-12-07) and no served releases (since 2026-12-08).
const EARLIER_MODEL: [&str; 12] = [
    "--penumbra",
    "iterated",
    "--surface",
    "flat",
    "--media",
    "first-order",
    "--subpixel-shadows",
    "false",
    "--horizon",
    "false",
    "--served-releases",
    "false",
];

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

/// The example scenes in file-name order; those reading ../shared/models or ../shared/volumes
/// only where that folder exists.
fn example_scenes() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes");
    let mut paths: Vec<PathBuf> = std::fs::read_dir(&dir)
        .unwrap()
        .map(|e| e.unwrap().path())
        .filter(|p| p.extension().is_some_and(|e| e == "toml"))
        .filter(|p| support::example_scene_inputs_present(p))
        .collect();
    paths.sort();
    assert!(paths.len() >= 5, "expected the example scenes in scenes/");
    paths
}

fn golden_path(file: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join(file)
}

/// `key → (image_hash, ldi_hash)` from a golden file.
pub(crate) fn read_golden(file: &str) -> BTreeMap<String, (String, String)> {
    let text = std::fs::read_to_string(golden_path(file)).expect(file);
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
        // Only the defaults' table: the others are earlier defaults' bits.
        let mut text = String::from(
            "# key\timage_hash\tldi_hash — written by CONVSHADOW_RECORD_GOLDEN=1 (see \
             tests/contract/golden_hashes.rs)\n",
        );
        for (key, scene, args) in cases() {
            let args: Vec<&str> = args.iter().map(String::as_str).collect();
            let (image, ldi) = hashes(&scene, &args, &dir);
            text += &format!("{key}\t{image}\t{ldi}\n");
        }
        std::fs::write(golden_path(GOLDEN), text).unwrap();
        return;
    }
    let checked = check_table(GOLDEN, &[], true, &dir);
    assert!(checked > 100, "only {checked} cases checked");
}

#[test]
fn every_example_scene_and_kernel_keeps_the_iterated_bits() {
    let dir = support::temp_dir("golden-iterated");
    let checked = check_table(GOLDEN_ITERATED, &EARLIER_MODEL, true, &dir);
    assert!(checked > 100, "only {checked} cases checked");
}

#[test]
fn every_example_scene_and_kernel_keeps_the_starting_bits_without_a_guard_band() {
    let dir = support::temp_dir("golden-band0");
    let extra: Vec<&str> = ["--guard-band", "0"]
        .into_iter()
        .chain(EARLIER_MODEL)
        .collect();
    let checked = check_table(GOLDEN_BAND0, &extra, false, &dir);
    assert!(checked > 100, "only {checked} cases checked");
}

/// Renders every case with `extra` arguments and compares with `file` (every case must be in
/// it when `complete`, else cases of scenes it does not know are skipped); returns the count.
fn check_table(file: &str, extra: &[&str], complete: bool, dir: &Path) -> usize {
    let golden = read_golden(file);
    let mut checked = 0;
    for (key, scene, args) in cases() {
        let Some(want) = golden.get(&key) else {
            assert!(!complete, "{key} is not in {file}");
            continue;
        };
        let base: Vec<&str> = args
            .iter()
            .map(String::as_str)
            .chain(extra.iter().copied())
            .collect();
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
            let got = hashes(&scene, &all, dir);
            assert_eq!(
                &got, want,
                "{file}: {key} {variant:?}: (image_hash, ldi_hash) changed"
            );
            checked += 1;
        }
    }
    checked
}

#[test]
fn the_golden_check_can_fail() {
    // Guards the guard: another seed is another image, so a changed image cannot pass.
    let dir = support::temp_dir("golden-fail");
    let golden = read_golden(GOLDEN);
    let scene = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenes/default.toml");
    let args = [
        "--width", "53", "--height", "40", "--slabs", "24", "--kernel", "ellipse2", "--seed", "7",
    ];
    let got = hashes(&scene, &args, &dir);
    assert_ne!(got.0, golden["default/ellipse2/53x40x24"].0);
}
