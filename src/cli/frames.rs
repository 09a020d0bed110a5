//! Animation frames of `convshadow render` (`--frames A..B`, `--frame K`, `--time-step DT`) and
//! the command line's view overrides (`--size WxH`, camera values).
//!
//! Frame `k` renders every detail material at time `t0 + k·dt`, where `t0` is the material's own
//! `detail.time` (0 for 3D noise, which becomes 4D noise). Each frame is independent, so frame `k`
//! alone (`--frame k`) gives the same bits as frame `k` of a sequence.

use std::path::{Path, PathBuf};

use convshadow_common::model::scene::Scene;

use crate::cli::exit::{self, Failure};

/// Default `--time-step`: detail time advanced per frame.
pub const DEFAULT_TIME_STEP: f64 = 0.05;

/// Most frames one `--frames` run renders: every frame's output paths are checked before the
/// first is rendered, so the list is held in memory (4 bytes a frame, and its paths).
pub const MAX_FRAMES: u32 = 1_000_000;

/// The frames to render: a half-open range of frame numbers.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FrameRange {
    /// First frame.
    pub start: u32,
    /// One past the last frame.
    pub end: u32,
}

impl FrameRange {
    /// Parses `A..B` (B excluded) or `A..=B` (B included).
    pub fn parse(text: &str) -> Result<FrameRange, String> {
        let bad = || format!("expected A..B or A..=B with frame numbers A < B, got `{text}`");
        let (a, b, inclusive) = if let Some((a, b)) = text.split_once("..=") {
            (a, b, true)
        } else if let Some((a, b)) = text.split_once("..") {
            (a, b, false)
        } else {
            return Err(bad());
        };
        let start: u32 = a.trim().parse().map_err(|_| bad())?;
        let b: u32 = b.trim().parse().map_err(|_| bad())?;
        let end = if inclusive {
            b.checked_add(1).ok_or_else(bad)?
        } else {
            b
        };
        if end <= start {
            return Err(bad());
        }
        if end - start > MAX_FRAMES {
            return Err(format!(
                "`{text}` asks for {} frames, at most {MAX_FRAMES} in one run (split a longer \
                 sequence into several runs, as docs/scale-out.md does)",
                end - start
            ));
        }
        Ok(FrameRange { start, end })
    }
}

/// Whether `path` has a frame-number pattern (`%d` or `%0Nd`).
pub fn has_frame_pattern(path: &Path) -> bool {
    find_pattern(&path.to_string_lossy()).is_some()
}

/// The widest zero padding a frame pattern may ask for (`%020d`): a `u32` frame number has at
/// most 10 digits; wider is refused as a bad argument rather than formatted (a width beyond
/// `u16::MAX` made `format!` panic, one of millions wrote a name no file system takes).
pub const MAX_PATTERN_WIDTH: usize = 20;

/// Why `path`'s frame pattern cannot be used (`None` when it has none or a usable one).
pub fn pattern_error(path: &Path) -> Option<String> {
    let (_, _, width) = find_pattern(&path.to_string_lossy())?;
    (width > MAX_PATTERN_WIDTH).then(|| {
        format!(
            "{}: the frame number pattern pads to at most {MAX_PATTERN_WIDTH} digits (%0{MAX_PATTERN_WIDTH}d)",
            path.display()
        )
    })
}

/// The first `%d` / `%0Nd` in `s`: (start byte, end byte, zero-padded width; `usize::MAX` when
/// the width's digits overflow).
fn find_pattern(s: &str) -> Option<(usize, usize, usize)> {
    let b = s.as_bytes();
    let mut i = 0;
    while i < b.len() {
        if b[i] == b'%' {
            let mut j = i + 1;
            while j < b.len() && b[j].is_ascii_digit() {
                j += 1;
            }
            if j < b.len() && b[j] == b'd' {
                let digits = &s[i + 1..j];
                let width = if digits.is_empty() {
                    0
                } else {
                    digits.parse().unwrap_or(usize::MAX)
                };
                return Some((i, j + 1, width));
            }
        }
        i += 1;
    }
    None
}

/// `path` with its first `%d` / `%0Nd` replaced by `frame` (unchanged without a pattern).
pub fn frame_path(path: &Path, frame: u32) -> PathBuf {
    let s = path.to_string_lossy();
    match find_pattern(&s) {
        Some((a, b, width)) => {
            // `pattern_error` refuses wider patterns before any frame; never a panic here.
            let width = width.min(MAX_PATTERN_WIDTH);
            PathBuf::from(format!("{}{frame:0width$}{}", &s[..a], &s[b..]))
        }
        None => path.to_path_buf(),
    }
}

/// The scene at frame `frame`: every detail material's time set to `t0 + frame·dt`.
pub fn scene_at_frame(scene: &Scene, frame: u32, dt: f64) -> Scene {
    let mut s = scene.clone();
    for m in &mut s.materials {
        if let Some(d) = &mut m.detail {
            d.time = Some(d.time.unwrap_or(0.0) + f64::from(frame) * dt);
        }
    }
    s
}

/// The detail time of frame `frame` (of the first detail material), for stats.
pub fn frame_time(scene: &Scene, frame: u32, dt: f64) -> Option<f64> {
    scene
        .materials
        .iter()
        .find_map(|m| m.detail.as_ref())
        .map(|d| d.time.unwrap_or(0.0) + f64::from(frame) * dt)
}

/// Refuses frames whose detail time leaves the scene format's range (`|detail.time| <= 1e9`,
/// `scene::MAX_WORLD`): `--time-step` could push it there (the noise then went flat, exit 0).
/// Times grow or fall with the frame number, so the first and last frame are the extremes.
pub fn check_times(scene: &Scene, list: &[u32], dt: f64) -> Result<(), Failure> {
    let max = convshadow_common::model::scene::MAX_WORLD;
    for &k in [list.first(), list.last()].into_iter().flatten() {
        for m in &scene.materials {
            let Some(d) = &m.detail else { continue };
            let t = d.time.unwrap_or(0.0) + f64::from(k) * dt;
            if t.is_nan() || t.abs() > max {
                return Err(Failure::new(
                    exit::BAD_ARGUMENTS,
                    format!(
                        "--time-step {dt}: frame {k} sets material.{}.detail.time to {t:e}, \
                         beyond the range |time| <= {max:e}; use a smaller step or fewer frames",
                        m.name
                    ),
                ));
            }
        }
    }
    Ok(())
}

/// A frame's detail time as printed: 12 significant digits, shortest form (`0.3`, not the
/// `0.30000000000000004` that 6 × 0.05 is in binary; the render uses the exact value).
pub fn display_time(t: f64) -> String {
    let rounded: f64 = format!("{t:.11e}").parse().unwrap_or(t);
    format!("{rounded}")
}

/// Parses `WxH` (also `W×H`, `W,H`).
pub fn parse_size(text: &str) -> Result<(u32, u32), String> {
    let bad = || format!("expected WxH in pixels, like 800x600, got `{text}`");
    let (w, h) = text.split_once(['x', 'X', '×', ',']).ok_or_else(bad)?;
    Ok((
        w.trim().parse().map_err(|_| bad())?,
        h.trim().parse().map_err(|_| bad())?,
    ))
}

/// Parses three comma-separated numbers `X,Y,Z`.
pub fn parse_vec3(text: &str) -> Result<[f64; 3], String> {
    let parts: Vec<&str> = text.split(',').map(str::trim).collect();
    let bad = || format!("expected three numbers X,Y,Z, got `{text}`");
    if parts.len() != 3 {
        return Err(bad());
    }
    let mut v = [0.0; 3];
    for (o, p) in v.iter_mut().zip(parts) {
        *o = p.parse().map_err(|_| bad())?;
    }
    Ok(v)
}

/// Applies `--size WxH`: the image becomes W×H and, when the aspect changes, `view_width` grows
/// so the scene's whole original view (its width and its height) stays in frame (a perspective
/// camera keeps its vertical field of view instead). Returns the note to print when
/// `view_width` changed.
pub fn apply_size(scene: &mut Scene, w: u32, h: u32) -> Result<Option<String>, Failure> {
    if w == 0 || h == 0 {
        return Err(Failure::new(
            exit::BAD_ARGUMENTS,
            format!("--size {w}x{h}: expected both sides >= 1"),
        ));
    }
    // The same aspect, compared exactly in integers: the view stays as it is (in floats,
    // view_width·(h/w)·(W/H) could come back one ulp off and "change" view_width).
    let (old_w, old_h) = (u64::from(scene.image.width), u64::from(scene.image.height));
    // A perspective camera keeps its vertical field of view: a wider image shows more across.
    if u64::from(w) * old_h == u64::from(h) * old_w || scene.camera.is_perspective() {
        scene.image.width = w;
        scene.image.height = h;
        return Ok(None);
    }
    let old_w = f64::from(scene.image.width);
    let old_h = f64::from(scene.image.height);
    let view_w = scene.camera.view_width;
    let view_h = view_w * old_h / old_w;
    // Pixels are square: the new view is view_width wide and view_width·h/w high.
    let needed = view_w.max(view_h * f64::from(w) / f64::from(h));
    scene.image.width = w;
    scene.image.height = h;
    let note = (needed != view_w).then(|| {
        scene.camera.view_width = needed;
        format!(
            "--size {w}x{h}: the aspect changes from {old_w}:{old_h} to {w}:{h}; \
             camera.view_width {view_w} → {needed} keeps the scene's view ({view_w} × {view_h} \
             world units) in frame"
        )
    });
    Ok(note)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_range_longer_than_max_frames_is_refused_before_any_list() {
        let ok = format!("7..{}", 7 + MAX_FRAMES);
        assert_eq!(
            FrameRange::parse(&ok).map(|r| r.end - r.start),
            Ok(MAX_FRAMES)
        );
        let e = FrameRange::parse("0..4000000000").unwrap_err();
        assert!(
            e.contains("4000000000 frames") && e.contains("at most 1000000"),
            "{e}"
        );
        let e = FrameRange::parse("0..=4294967294").unwrap_err();
        assert!(e.contains("4294967295 frames"), "{e}");
    }

    #[test]
    fn ranges_patterns_and_sizes_parse() {
        assert_eq!(
            FrameRange::parse("0..4"),
            Ok(FrameRange { start: 0, end: 4 })
        );
        assert_eq!(
            FrameRange::parse("2..=3"),
            Ok(FrameRange { start: 2, end: 4 })
        );
        assert!(FrameRange::parse("3..3").is_err());
        assert!(FrameRange::parse("x").is_err());
        assert_eq!(
            frame_path(Path::new("out/f_%04d.png"), 7),
            PathBuf::from("out/f_0007.png")
        );
        assert_eq!(
            frame_path(Path::new("f%d.exr"), 12),
            PathBuf::from("f12.exr")
        );
        assert_eq!(
            frame_path(Path::new("plain.png"), 3),
            PathBuf::from("plain.png")
        );
        assert!(!has_frame_pattern(Path::new("100%.png")));
        assert_eq!(parse_size("800x600"), Ok((800, 600)));
        assert!(parse_size("800").is_err());
        assert_eq!(parse_vec3("1, 0,-2.5"), Ok([1.0, 0.0, -2.5]));
        assert!(parse_vec3("1,2").is_err());
    }

    #[test]
    fn size_keeps_the_whole_view_in_frame() {
        let mut s = Scene::default_scene();
        let v = s.camera.view_width;
        // Same aspect: nothing changes but the pixel count.
        assert_eq!(apply_size(&mut s, 256, 256).unwrap(), None);
        assert_eq!(s.camera.view_width, v);
        // Wider: view_width grows so the height still shows all of the old view.
        assert!(apply_size(&mut s, 512, 256).unwrap().is_some());
        assert_eq!(s.camera.view_width, 2.0 * v);
        // Taller: the width already holds the old view (which is now 2v × v).
        assert_eq!(apply_size(&mut s, 512, 512).unwrap(), None);
        // The same aspect where floats round: 1×7 px, 1.1 wide, to 5×35 (was 1.1000000000000003).
        s.image.width = 1;
        s.image.height = 7;
        s.camera.view_width = 1.1;
        assert_eq!(apply_size(&mut s, 5, 35).unwrap(), None);
        assert_eq!(s.camera.view_width, 1.1);
        assert_eq!((s.image.width, s.image.height), (5, 35));
    }
}
