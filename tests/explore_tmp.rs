//! The distance penumbra (issue: shadows right at every distance).

use convshadow::common::scene::Penumbra;
use convshadow::cpu::reference::edge::{EdgeSetup, half_crossing, model_profile, width_10_90};

/// The edge at distance `d` = k·d1 (d1 = 1): pixels of d/64 (so the correct penumbra is
/// 64·σ px wide at every distance), 256 px across, `slabs` slabs between occluder and receiver.
fn edge_at(k: f64, slabs: u32, penumbra: Penumbra, aniso: bool) -> EdgeSetup {
    let d = k;
    EdgeSetup {
        slabs,
        slab_distance: d / f64::from(slabs),
        optimal_distance: 1.0,
        pixel_size: d / 64.0,
        width: 256,
        height: 48,
        tilt_deg: 30.0,
        variance: if aniso { 0.02 } else { 0.01 },
        variance_y: aniso.then_some(0.005),
        rotation_deg: if aniso { 30.0 } else { 0.0 },
        penumbra,
        kernel: "ellipse2".into(),
        compensation: true,
        seed: 0,
    }
}

#[test]
fn explore() {
    for aniso in [false, true] {
        for k in [1.0] {
            for pen in [Penumbra::Iterated, Penumbra::Distance] {
                for slabs in [64u32, 200, 256, 512] {
                    let s = edge_at(k, slabs, pen, aniso);
                    let (profile, secs) = s.profile();
                    let from = s.first_trusted_column();
                    let std = s.distance() * s.variance_across().sqrt() / s.pixel_size;
                    let want = model_profile(profile.len(), s.expected_isoline(), std);
                    let to = profile.len() - 8;
                    let rmse = ((from..to)
                        .map(|x| (profile[x] - want[x]).powi(2))
                        .sum::<f64>()
                        / (to - from) as f64)
                        .sqrt();
                    let iso =
                        half_crossing(&profile, from).unwrap_or(f64::NAN) - s.expected_isoline();
                    let w = width_10_90(&profile, from).unwrap_or(f64::NAN);
                    let ww = width_10_90(&want, from).unwrap_or(f64::NAN);
                    println!(
                        "aniso {aniso} k {k} {pen} slabs {slabs}: rmse {rmse:.5} iso {iso:+.3} width {w:.3} vs {ww:.3} ({:+.2}%) {secs:.3}s",
                        100.0 * (w / ww - 1.0)
                    );
                }
            }
        }
    }
}
