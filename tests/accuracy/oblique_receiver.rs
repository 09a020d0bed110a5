//! An opaque receiver oblique to the slabs (issue 40): it must not shadow itself (the surface
//! hold, `common/src/plan/surface_hold.rs`), and the shadow an opaque edge casts on it must stay
//! the closed-form one. Expected values are the Gaussian CDF of the edge's penumbra at each
//! pixel's own distance to the edge, computed here from the geometry (Patel et al. 2013
//! appendix A.3: the correct shadow has standard deviation d·σ, the iterated model's √(d·d1)·σ).

use std::path::Path;

use convshadow::common::model::scene::{Penumbra, Scene};
use convshadow::pipeline::{CpuPath, RenderRequest, render};
use convshadow::reference::edge::phi;

/// Image size (pixels), view width (world units).
const SIZE: u32 = 160;
const VIEW: f64 = 2.0;
/// The light's variance on the unit light plane and its tilt: along camera x so that the edge's
/// shadow falls beside the occluder, where the camera sees it (shadows move by −d·tan ω), and
/// along camera y, the receiver's slope.
const VARIANCE: f64 = 0.0025;
const TILT_X: f64 = -25.0;
const TILT_Y: f64 = 15.0;
/// The iterated model's d1.
const D1: f64 = 1.0;
/// The receiver's thickness, and the gap between the occluder and the receiver's nearest point.
const THICK: f64 = 0.1;
const GAP: f64 = 0.2;
/// The occluder's thickness. Its front face casts the edge's shadow: every direction of the
/// light travels towards +x (its spread, 0.05, is far below the tilt's tan 25° = 0.47), so the
/// ray past the edge grazes the front corner (before 2026-12-05 the test measured the distance
/// from the back face, 0.02 too short: the closed form's line 0.75 px too near the edge).
const OCC_THICK: f64 = 0.02;
/// The RMSE asked over the receiver: issue 40's 5e-3 (measured 2026-12-08, docs/accuracy.md
/// §2b: 9e-4–3.5e-3 for both penumbra models at 30° and 60°, 7.4e-4 at 60° and 2048 slabs). The distance penumbra at 60°
/// reaches it only with released light served on its surface (`sweep.served_releases`: without
/// it 0.0087 and 0.0124, the receiver's released zeros and depths read by its own pixels in the
/// occluder's penumbra). Without sub-pixel shadows the line lies on pixel boundaries, up to
/// 0.8 px off (0.009–0.028); without the surface hold, 0.22–0.33 and lit std/mean 0.27–0.91.
const ASKED_RMSE: f64 = 5e-3;

/// One oblique receiver: a white opaque plate turned `tilt` degrees about world x, under an
/// opaque half-plane facing the camera that covers world x ≥ 0 (the image's left half); the
/// receiver is seen in the right half, where the edge's shadow falls.
struct Oblique {
    tilt: f64,
    slabs: u32,
    penumbra: Penumbra,
    kernel: &'static str,
    /// `sweep.subpixel_shadows`.
    subpixel: bool,
    /// `sweep.served_releases`.
    served: bool,
}

impl Oblique {
    /// Depth of the receiver's front face at world height y (the plate is centred at z = 0).
    fn receiver_depth(&self, y: f64) -> f64 {
        let t = self.tilt.to_radians();
        -0.5 * THICK / t.cos() + y * t.tan()
    }

    /// The occluder's back face: `GAP` in front of the receiver's nearest point in view.
    fn occluder_depth(&self) -> f64 {
        let half = 0.5 * VIEW;
        self.receiver_depth(-half).min(self.receiver_depth(half)) - GAP
    }

    fn scene(&self) -> Scene {
        let penumbra = match self.penumbra {
            Penumbra::Iterated => "iterated",
            Penumbra::Distance => "distance",
        };
        let text = format!(
            r#"
[image]
width = {SIZE}
height = {SIZE}
[camera]
view_width = {VIEW}
[sweep]
slabs = {slabs}
penumbra = "{penumbra}"
kernel = "{kernel}"
optimal_distance = {D1}
subpixel_shadows = {sp}
served_releases = {served}
[[light]]
tilt_deg = [{TILT_X}, {TILT_Y}]
variance = [{VARIANCE}, {VARIANCE}]
[[mesh]]
shape = "box"
size = [4.0, 6.0, {OCC_THICK}]
translate = [2.0, 0.0, {ze}]
material = "white"
[[mesh]]
shape = "box"
size = [4.0, 6.0, {THICK}]
rotate_deg = [{tilt}, 0.0, 0.0]
material = "white"
[material.white]
opacity = 1.0
surface = "flat"  # the light itself, without the cosine: the shadow is measured
"#,
            slabs = self.slabs,
            kernel = self.kernel,
            ze = self.occluder_depth() - 0.5 * OCC_THICK,
            tilt = self.tilt,
            sp = self.subpixel,
            served = self.served,
        );
        Scene::parse(&text, "oblique.toml", Path::new(".")).unwrap_or_else(|e| panic!("{e}"))
    }

    /// The closed-form light at pixel (x, y), or `None` where the camera sees the occluder: the
    /// edge at camera x = 0 (world x = 0; the occluder covers camera x ≤ 0) casts its half-shadow
    /// line at x = −d·tan ωx, d the pixel's distance to the occluder's front face, with a penumbra of standard
    /// deviation d·σ (distance) or √(d·d1)·σ (iterated). A tilt along y moves the shadow along
    /// the edge only.
    fn expected(&self, x: u32, y: u32) -> Option<f64> {
        let px = VIEW / f64::from(SIZE);
        let cx = (f64::from(x) + 0.5 - 0.5 * f64::from(SIZE)) * px;
        let world_y = -(f64::from(y) + 0.5 - 0.5 * f64::from(SIZE)) * px;
        let d = self.receiver_depth(world_y) - (self.occluder_depth() - OCC_THICK);
        let sigma = VARIANCE.sqrt();
        let std = match self.penumbra {
            Penumbra::Distance => d * sigma,
            Penumbra::Iterated => (d * D1).sqrt() * sigma,
        };
        (cx > 0.0).then(|| phi((cx + d * TILT_X.to_radians().tan()) / std))
    }

    /// Renders (SIMD path) and returns (RMSE against the closed form over the receiver, the lit
    /// region's standard deviation relative to its mean, and the lit pixels counted).
    fn measure(&self) -> (f64, f64, usize) {
        self.measure_on(CpuPath::Simd, 0).0
    }

    /// [`Oblique::measure`] on `path` with `threads` (0: one per core), and the image's hash.
    fn measure_on(&self, path: CpuPath, threads: usize) -> ((f64, f64, usize), u64) {
        let scene = self.scene();
        let req = RenderRequest {
            path,
            threads,
            ..RenderRequest::default()
        };
        let out = render(&scene, &req).unwrap_or_else(|e| panic!("{e}"));
        let (hash, image) = (out.image_hash, out.image);
        let (mut sq, mut n) = (0.0f64, 0usize);
        let mut lit = Vec::new();
        for y in 0..SIZE {
            for x in 0..SIZE {
                let v = f64::from(image.data[3 * (y * SIZE + x) as usize]);
                let Some(want) = self.expected(x, y) else {
                    continue;
                };
                sq += (v - want) * (v - want);
                n += 1;
                if want > 1.0 - 1e-9 {
                    lit.push(v);
                }
            }
        }
        let mean = lit.iter().sum::<f64>() / lit.len() as f64;
        let var = lit.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / lit.len() as f64;
        (((sq / n as f64).sqrt(), var.sqrt() / mean, lit.len()), hash)
    }
}

#[test]
fn an_oblique_receiver_does_not_shadow_itself_and_keeps_the_edge_shadow() {
    let mut report = Vec::new();
    let mut failed = false;
    for penumbra in [Penumbra::Distance, Penumbra::Iterated] {
        for tilt in [30.0, 60.0] {
            // And at 2048 slabs where the served releases matter: their age grows with the
            // slab count (`surface_hold::served_release_slabs`; 8 slabs there gave 0.0043).
            let counts: &[u32] = if penumbra == Penumbra::Distance && tilt == 60.0 {
                &[128, 512, 2048]
            } else {
                &[128, 512]
            };
            for &slabs in counts {
                let case = Oblique {
                    tilt,
                    slabs,
                    penumbra,
                    kernel: "ellipse2",
                    subpixel: true,
                    served: true,
                };
                let (rmse, banding, lit) = case.measure();
                let mut line = format!(
                    "{penumbra:?} {tilt}° {slabs} slabs: RMSE {rmse:.5} (≤ {ASKED_RMSE}), lit std/mean {banding:.2e} over {lit} px"
                );
                failed |= rmse > ASKED_RMSE || banding > 1e-3 || lit < 1000;
                // Without served releases the distance penumbra at 60° misses it (so the rule
                // is exercised here).
                if penumbra == Penumbra::Distance && tilt == 60.0 {
                    let unserved = Oblique {
                        served: false,
                        ..case
                    };
                    let (rmse_unserved, _, _) = unserved.measure();
                    line += &format!("; without served releases: {rmse_unserved:.5}");
                    failed |= rmse_unserved <= ASKED_RMSE;
                }
                // The same without sub-pixel shadows: the line on pixel boundaries.
                let carried = Oblique {
                    subpixel: false,
                    ..case
                };
                let (rmse_carried, _, _) = carried.measure();
                line += &format!("; carried in whole pixels: {rmse_carried:.5}");
                failed |= tilt == 30.0 && rmse_carried <= ASKED_RMSE;
                report.push(line);
            }
        }
    }
    let report = report.join("\n");
    println!("{report}");
    assert!(
        !failed,
        "asked: RMSE as shown (and above {ASKED_RMSE} at 30° when carried, so the check can \
         fail), lit std/mean ≤ 1e-3\n{report}"
    );
}

#[test]
fn an_oblique_receiver_does_not_shadow_itself_with_any_kernel() {
    // The banding half of the test above for every kernel, 60° and 512 slabs (the steepest and
    // finest case), both penumbra models. Measured: lit std/mean ≤ 5.4e-5 for every kernel.
    let mut report = Vec::new();
    let mut failed = false;
    for penumbra in [Penumbra::Distance, Penumbra::Iterated] {
        for kernel in crate::support::kernels() {
            let case = Oblique {
                tilt: 60.0,
                slabs: 512,
                penumbra,
                kernel,
                subpixel: true,
                served: true,
            };
            let (rmse, banding, lit) = case.measure();
            // The RMSE is printed only: the kernels' penumbra shapes differ (`box` 0.050).
            failed |= banding > 1e-3 || lit < 1000;
            report.push(format!(
                "{penumbra:?} {kernel}: RMSE {rmse:.5}, lit std/mean {banding:.2e} over {lit} px"
            ));
        }
    }
    let report = report.join("\n");
    println!("{report}");
    assert!(!failed, "asked: lit std/mean ≤ 1e-3\n{report}");
}

#[test]
fn served_releases_give_the_same_bits_on_every_path_and_thread_count() {
    // The 60° receiver, where released light is served (the test above: the RMSE needs it):
    // the scalar path on one thread against the SIMD path on one and on eight, both penumbrae.
    for penumbra in [Penumbra::Distance, Penumbra::Iterated] {
        let case = Oblique {
            tilt: 60.0,
            slabs: 128,
            penumbra,
            kernel: "ellipse2",
            subpixel: true,
            served: true,
        };
        let (_, scalar) = case.measure_on(CpuPath::Scalar, 1);
        for threads in [1, 8] {
            let (_, simd) = case.measure_on(CpuPath::Simd, threads);
            assert_eq!(simd, scalar, "{penumbra:?}: SIMD on {threads} threads");
        }
        let (_, unserved) = Oblique {
            served: false,
            ..case
        }
        .measure_on(CpuPath::Scalar, 1);
        assert_ne!(unserved, scalar, "{penumbra:?}: no release was served");
    }
}
