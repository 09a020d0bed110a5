//! The output files of `convshadow render`, checked before any work (a refusal costs no render):
//! the defaults, frame-number patterns, image extensions, collisions between outputs, and
//! whether each can be written.

use std::path::PathBuf;

use convshadow_common::model::scene::Scene;

use super::args::{RenderArgs, RenderBackend};
use crate::cli::exit::{self, Failure};
use crate::cli::frames;

/// The output files (defaults, frame patterns), checked before any work for every frame of
/// `frame_list`: writable (each name, and each folder once), not colliding with one another on
/// any frame, with an image extension, and not one of the scene's input files.
pub(super) fn output_paths(
    args: &RenderArgs,
    frame_list: Option<&[u32]>,
    scene: &Scene,
) -> Result<Vec<PathBuf>, Failure> {
    let outputs = if args.outputs.is_empty() {
        match frame_list {
            Some(_) => vec![PathBuf::from("render_%04d.png")],
            None => vec![PathBuf::from("render.png")],
        }
    } else {
        args.outputs.clone()
    };
    if let Some(message) = outputs.iter().find_map(|p| frames::pattern_error(p)) {
        return Err(Failure::new(exit::BAD_ARGUMENTS, message));
    }
    if let Some(list) = frame_list
        && list.len() > 1
        && let Some(p) = outputs.iter().find(|p| !frames::has_frame_pattern(p))
    {
        return Err(Failure::new(
            exit::BAD_ARGUMENTS,
            format!(
                "{}: {} frames would overwrite one file; put a frame number pattern in the \
                 name, such as out_%04d.png",
                p.display(),
                list.len()
            ),
        ));
    }
    if args.backend == RenderBackend::Reference && frame_list.is_some() {
        return Err(Failure::new(
            exit::BAD_ARGUMENTS,
            "--frames/--frame do not apply to --backend reference",
        ));
    }
    // Every file the run writes, tagged (output index, frame): each output at each frame, then
    // the stats (index `outputs.len()`).
    let mut files: Vec<((usize, u32), PathBuf)> = Vec::new();
    match frame_list {
        Some(list) => {
            for &k in list {
                for (i, p) in outputs.iter().enumerate() {
                    files.push(((i, k), frames::frame_path(p, k)));
                }
            }
        }
        None => files.extend(
            outputs
                .iter()
                .cloned()
                .enumerate()
                .map(|(i, p)| ((i, 0), p)),
        ),
    }
    if let Some(p) = &args.stats_json {
        files.push(((outputs.len(), 0), p.clone()));
    }
    let name = |(i, k): (usize, u32)| match outputs.get(i) {
        Some(p) if frame_list.is_some() && frames::has_frame_pattern(p) => format!(
            "{} at frame {k} ({})",
            p.display(),
            frames::frame_path(p, k).display()
        ),
        Some(p) => p.display().to_string(),
        None => args
            .stats_json
            .as_ref()
            .map_or_else(String::new, |p| p.display().to_string()),
    };
    refuse_aov_misuse(args, &outputs)?;
    crate::cli::refuse_named_collisions(files.iter().map(|(t, p)| (*t, p.as_path())), name)?;
    crate::cli::refuse_outputs_over_inputs(
        files.iter().map(|(_, p)| p),
        &crate::cli::scene_inputs(args.scene.as_deref(), scene),
    )?;
    // Each name, then each folder once (a pattern may put frames in different folders).
    let mut folders = std::collections::HashSet::new();
    for (_, p) in &files {
        convshadow_io::image::check_target(p)?;
    }
    for p in &outputs {
        let ext = p
            .extension()
            .map(|e| e.to_string_lossy().to_ascii_lowercase());
        if !matches!(ext.as_deref(), Some("png" | "exr")) {
            return Err(Failure::new(
                exit::BAD_ARGUMENTS,
                format!(
                    "{}: unknown image extension; expected .png or .exr",
                    p.display()
                ),
            ));
        }
    }
    for (_, p) in &files {
        if folders.insert(convshadow_io::image::folder_of(p).to_path_buf()) {
            convshadow_io::image::check_folder(p)?;
        }
    }
    Ok(outputs)
}

/// `--aov` layers go into EXR files only: refused (a usage error naming the flag) with a PNG
/// output, the default `render.png` included, and when a layer is named twice.
fn refuse_aov_misuse(args: &RenderArgs, outputs: &[PathBuf]) -> Result<(), Failure> {
    let Some(first) = args.aov.first() else {
        return Ok(());
    };
    if let Some(png) = outputs
        .iter()
        .find(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("png")))
    {
        return Err(Failure::new(
            exit::BAD_ARGUMENTS,
            format!(
                "--aov {}: {} is a PNG, which has no room for extra layers; write the layers to \
                 an .exr output (-o out.exr), and render the PNG without --aov",
                first.name(),
                png.display()
            ),
        ));
    }
    for (i, aov) in args.aov.iter().enumerate() {
        if args.aov[..i].contains(aov) {
            return Err(Failure::new(
                exit::BAD_ARGUMENTS,
                format!("--aov {}: named twice", aov.name()),
            ));
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::super::args::parse;
    use super::*;

    /// A fresh folder for one test, removed when the test ends.
    struct Dir(PathBuf);

    impl Dir {
        fn new(name: &str) -> Dir {
            let d =
                std::env::temp_dir().join(format!("convshadow-unit-{name}-{}", std::process::id()));
            let _ = std::fs::remove_dir_all(&d);
            std::fs::create_dir_all(&d).unwrap();
            Dir(d)
        }

        /// `name` in the folder, as a command-line argument.
        fn arg(&self, name: &str) -> String {
            self.0.join(name).display().to_string()
        }
    }

    impl Drop for Dir {
        fn drop(&mut self) {
            let _ = std::fs::remove_dir_all(&self.0);
        }
    }

    fn outputs(argv: &[&str], frames: Option<&[u32]>) -> Result<Vec<PathBuf>, Failure> {
        let args = parse(argv).unwrap_or_else(|e| panic!("{argv:?}: {e}"));
        output_paths(&args, frames, &Scene::default_scene())
    }

    fn refused(argv: &[&str], frames: Option<&[u32]>, code: i32, words: &str) {
        let f = outputs(argv, frames)
            .err()
            .unwrap_or_else(|| panic!("{argv:?} accepted"));
        assert_eq!(f.code, code, "{argv:?}: {}", f.message);
        assert!(f.message.contains(words), "{argv:?}: {}", f.message);
    }

    #[test]
    fn without_outputs_a_render_writes_render_png_and_a_sequence_a_numbered_pattern() {
        assert_eq!(outputs(&[], None).unwrap(), [PathBuf::from("render.png")]);
        assert_eq!(
            outputs(&[], Some(&[0, 1])).unwrap(),
            [PathBuf::from("render_%04d.png")]
        );
    }

    #[test]
    fn png_and_exr_outputs_in_any_case_are_kept_in_order_with_a_json_of_any_name() {
        let d = Dir::new("outputs-kept");
        let (a, b, s) = (d.arg("a.PNG"), d.arg("b.exr"), d.arg("stats.json"));
        let got = outputs(&["-o", &a, "-o", &b, "--stats-json", &s], None).unwrap();
        assert_eq!(got, [PathBuf::from(&a), PathBuf::from(&b)]);
        // Checking writes nothing that stays.
        assert_eq!(std::fs::read_dir(&d.0).unwrap().count(), 0);
    }

    #[test]
    fn other_extensions_are_refused_as_bad_arguments() {
        let d = Dir::new("outputs-ext");
        for name in ["a.jpg", "a", "a.png.txt"] {
            let p = d.arg(name);
            refused(
                &["-o", &p],
                None,
                exit::BAD_ARGUMENTS,
                "unknown image extension",
            );
        }
    }

    #[test]
    fn two_outputs_naming_one_file_are_refused_however_spelled() {
        let d = Dir::new("outputs-collide");
        let a = d.arg("a.png");
        let same = format!("{}/./a.png", d.0.display());
        refused(
            &["-o", &a, "-o", &same],
            None,
            exit::BAD_ARGUMENTS,
            "same file",
        );
        refused(
            &["-o", &a, "--stats-json", &a],
            None,
            exit::BAD_ARGUMENTS,
            "same file",
        );
        // A sequence checks every frame's names: f_%02d.png is f_03.png for frame 3.
        let pattern = d.arg("f_%02d.png");
        let first = d.arg("f_03.png");
        let argv = ["-o", pattern.as_str(), "--stats-json", first.as_str()];
        refused(&argv, Some(&[3, 4]), exit::BAD_ARGUMENTS, "same file");
        refused(&argv, Some(&[2, 3]), exit::BAD_ARGUMENTS, "at frame 3");
        assert!(outputs(&argv, Some(&[4, 5])).is_ok());
        // Two patterns that differ on frame 0 (f_0, f_00) but meet on frame 10 (f_10).
        let (a, b) = (d.arg("f_%d.png"), d.arg("f_%02d.png"));
        let argv = ["-o", a.as_str(), "-o", b.as_str()];
        assert!(outputs(&argv, Some(&[0, 1])).is_ok());
        refused(&argv, Some(&[9, 10]), exit::BAD_ARGUMENTS, "at frame 10");
    }

    #[test]
    fn a_sequence_needs_a_frame_pattern_in_every_output_but_one_frame_does_not() {
        let d = Dir::new("outputs-frames");
        let (plain, pattern) = (d.arg("f.png"), d.arg("f_%d.exr"));
        refused(
            &["-o", &pattern, "-o", &plain],
            Some(&[0, 1, 2]),
            exit::BAD_ARGUMENTS,
            "3 frames would overwrite one file",
        );
        assert_eq!(
            outputs(&["-o", &plain], Some(&[7])).unwrap(),
            [PathBuf::from(&plain)]
        );
        let reference = ["--backend", "reference", "-o", pattern.as_str()];
        refused(
            &reference,
            Some(&[0, 1]),
            exit::BAD_ARGUMENTS,
            "--backend reference",
        );
    }

    #[test]
    fn aov_layers_need_exr_outputs_and_each_layer_once() {
        let d = Dir::new("outputs-aov");
        let (png, exr) = (d.arg("a.png"), d.arg("a.exr"));
        let words = "--aov depth: ";
        refused(&["--aov", "depth"], None, exit::BAD_ARGUMENTS, words);
        refused(
            &["--aov", "depth", "-o", &exr, "-o", &png],
            None,
            exit::BAD_ARGUMENTS,
            "a.png is a PNG",
        );
        refused(
            &["--aov", "light0,depth,light0", "-o", &exr],
            None,
            exit::BAD_ARGUMENTS,
            "--aov light0: named twice",
        );
        let ok = outputs(&["--aov", "depth,light1", "-o", &exr], None).unwrap();
        assert_eq!(ok, [PathBuf::from(&exr)]);
    }

    #[test]
    fn an_output_that_cannot_be_written_is_an_output_failure_before_any_work() {
        let d = Dir::new("outputs-unwritable");
        let missing = d.arg("no/such/folder/a.png");
        refused(
            &["-o", &missing],
            None,
            exit::OUTPUT_FAILED,
            "does not exist",
        );
        let folder = d.0.display().to_string();
        refused(&["-o", &folder], None, exit::OUTPUT_FAILED, "is a folder");
        // A later frame's folder is checked too: o0 exists, o1 does not.
        std::fs::create_dir(d.0.join("o0")).unwrap();
        let pattern = d.arg("o%d/a.png");
        refused(&["-o", &pattern], Some(&[0, 1]), exit::OUTPUT_FAILED, "o1");
        assert!(outputs(&["-o", &pattern], Some(&[0])).is_ok());
        // Names a rename into place would refuse only after the render.
        let long = d.arg(&format!("{}.png", "x".repeat(252)));
        refused(&["-o", &long], None, exit::OUTPUT_FAILED, "at most 255");
        let slash = format!("{}/", d.arg("a.png"));
        refused(&["-o", &slash], None, exit::OUTPUT_FAILED, "names a folder");
    }
}
