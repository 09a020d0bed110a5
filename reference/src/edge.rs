//! The opaque-edge harness (paper appendix A.3): an opaque half-plane occluder in the
//! first slab and a fully transparent receiver `m` slabs behind it, so the light buffer after the
//! last slab is exactly the light the receiver gets after `m` convolutions. Shared by the
//! accuracy report, `tests/accuracy/sweep_accuracy.rs` and `tests/accuracy/hard_cases.rs`.

use std::path::Path;

use convshadow_common::model::scene::{Penumbra, Scene, SceneError};
use convshadow_common::plan::RenderPlan;
use convshadow_cpu::ldi::{BuildLdi, Ldi};
use convshadow_cpu::sweep::{SweepOptions, SweepOutput, sweep};

/// One edge set-up. The occluder covers world x ≥ 0, i.e. the image columns left of the centre
/// (column boundary `width / 2`); the receiver is `slabs` slabs of thickness `slab_distance`
/// behind it, at distance `d = slabs · slab_distance`.
#[derive(Clone, Debug, PartialEq)]
pub struct EdgeSetup {
    /// Convolutions between occluder and receiver.
    pub slabs: u32,
    /// Slab thickness e (world units).
    pub slab_distance: f64,
    /// Optimal shadow distance d1 (world units).
    pub optimal_distance: f64,
    /// Pixel size (world units).
    pub pixel_size: f64,
    /// Image width (pixels).
    pub width: u32,
    /// Image height (pixels).
    pub height: u32,
    /// Light tilt ωx (degrees); ωy = 0.
    pub tilt_deg: f64,
    /// Light variance σx² (and σy² unless `variance_y` is given).
    pub variance: f64,
    /// Light variance σy², if not σx².
    pub variance_y: Option<f64>,
    /// Rotation of the light's principal axes (degrees).
    pub rotation_deg: f64,
    /// How the kernels grow with depth.
    pub penumbra: Penumbra,
    /// Kernel name.
    pub kernel: String,
    /// `sweep.variance_compensation`.
    pub compensation: bool,
    /// `sweep.seed`.
    pub seed: u32,
}

/// What the analytic cases (edge, disk) share: the image, the slabs, the kernel, and a transparent
/// receiver box 0.2·e thick in the slab `slabs` behind an occluder 0.2·e thick in slab 0.
pub(crate) struct CaseFrame<'a> {
    pub width: u32,
    pub height: u32,
    pub pixel_size: f64,
    pub slab_distance: f64,
    pub optimal_distance: f64,
    pub kernel: &'a str,
    pub compensation: bool,
    pub slabs: u32,
}

impl CaseFrame<'_> {
    /// The scene text: `sweep_extra` adds `[sweep]` keys, `light` is the one `[[light]]`'s keys,
    /// `occluder` the occluder `[[mesh]]`'s keys but its material.
    pub(crate) fn toml(&self, sweep_extra: &str, light: &str, occluder: &str) -> String {
        let e = self.slab_distance;
        format!(
            r#"
[image]
width = {w}
height = {h}
[camera]
view_width = {vw:e}
[sweep]
guard_band = 0  # the analytic references read the grid as the image
slab_distance = {e:e}
optimal_distance = {d1:e}
kernel = "{kernel}"
variance_compensation = {comp}
{sweep_extra}[[light]]
{light}[[mesh]]
{occluder}material = "occluder"
[[mesh]]
shape = "box"
size = [20.0, 20.0, {rec_size:e}]
translate = [0.0, 0.0, {rec_z:e}]
material = "receiver"
[material.occluder]
[material.receiver]
transport = [1.0, 1.0, 1.0]
"#,
            w = self.width,
            h = self.height,
            vw = f64::from(self.width) * self.pixel_size,
            d1 = self.optimal_distance,
            kernel = self.kernel,
            comp = self.compensation,
            rec_size = 0.2 * e,
            rec_z = (f64::from(self.slabs) + 0.4) * e,
        )
    }
}

impl EdgeSetup {
    /// The set-up of `tests/accuracy/sweep_accuracy.rs`: e = 0.01, d1 = 0.16, 512 × 96 pixels of 0.01.
    pub fn classic(slabs: u32, tilt_deg: f64, variance: f64, kernel: &str) -> EdgeSetup {
        EdgeSetup {
            slabs,
            slab_distance: 0.01,
            optimal_distance: 0.16,
            pixel_size: 0.01,
            width: 512,
            height: 96,
            tilt_deg,
            variance,
            variance_y: None,
            rotation_deg: 0.0,
            penumbra: Penumbra::Iterated,
            kernel: kernel.to_string(),
            compensation: true,
            seed: 0,
        }
    }

    /// The light's variance across the edge (along x), σx² cos²α + σy² sin²α: the correct
    /// penumbra's standard deviation is d·√ of it.
    pub fn variance_across(&self) -> f64 {
        let (s, c) = self.rotation_deg.to_radians().sin_cos();
        c * c * self.variance + s * s * self.variance_y.unwrap_or(self.variance)
    }

    /// Distance d from occluder to receiver (world units).
    pub fn distance(&self) -> f64 {
        f64::from(self.slabs) * self.slab_distance
    }

    /// The scene text (TOML).
    pub fn toml(&self) -> String {
        let e = self.slab_distance;
        CaseFrame {
            width: self.width,
            height: self.height,
            pixel_size: self.pixel_size,
            slab_distance: e,
            optimal_distance: self.optimal_distance,
            kernel: &self.kernel,
            compensation: self.compensation,
            slabs: self.slabs,
        }
        .toml(
            &format!("seed = {}\npenumbra = \"{}\"\n", self.seed, self.penumbra),
            &format!(
                "tilt_deg = [{tilt:e}, 0.0]\nvariance = [{var:e}, {var_y:e}]\n\
                 rotation_deg = {rot:e}\n",
                tilt = self.tilt_deg,
                var = self.variance,
                var_y = self.variance_y.unwrap_or(self.variance),
                rot = self.rotation_deg,
            ),
            &format!(
                "shape = \"box\"\nsize = [20.0, 20.0, {:e}]\ntranslate = [10.0, 0.0, {:e}]\n",
                0.2 * e,
                0.4 * e
            ),
        )
    }

    /// The parsed scene.
    pub fn scene(&self) -> Result<Scene, SceneError> {
        Scene::parse(&self.toml(), "<edge case>", Path::new("."))
    }

    /// Where the half-shadow isoline is expected (pixel coordinate along x): the edge's image
    /// column boundary moved by −d·tan ω.
    pub fn expected_isoline(&self) -> f64 {
        f64::from(self.width) / 2.0
            - self.distance() * self.tilt_deg.to_radians().tan() / self.pixel_size
    }

    /// First column whose values are trusted: left of it, reads outside the buffer (which see
    /// unoccluded light) have leaked in.
    pub fn first_trusted_column(&self) -> usize {
        (self.width as usize / 8).max(4)
    }

    /// Renders and returns the light profile across the edge (see [`edge_profile`]) and the
    /// sweep's time in seconds.
    pub fn profile(&self) -> (Vec<f64>, f64) {
        let scene = self.scene().unwrap_or_else(|e| panic!("{e}"));
        let (plan, out, seconds) = run_light(&scene, None);
        assert_eq!(
            plan.slabs,
            self.slabs + 1,
            "the receiver must be crossed in the last slab"
        );
        (edge_profile(&plan, &out), seconds)
    }
}

/// Builds the initial light buffer of a sweep from its plan.
pub type InitialLight<'a> = &'a dyn Fn(&RenderPlan) -> Vec<f32>;

/// Runs geometry → LDI → plan → sweep on the current rayon pool; returns the plan, the sweep's
/// output and the sweep's time in seconds. `initial` builds the initial light buffer.
pub fn run_light(
    scene: &Scene,
    initial: Option<InitialLight<'_>>,
) -> (RenderPlan, SweepOutput, f64) {
    let g = convshadow_io::build_geometry(scene).unwrap_or_else(|e| panic!("{e}"));
    let ldi = Ldi::build(&g.raster, 8 << 30).unwrap_or_else(|e| panic!("{e}"));
    let plan = convshadow_io::build_plan(scene, &g).unwrap_or_else(|e| panic!("{e}"));
    let init = initial.map(|f| f(&plan));
    let options = SweepOptions {
        initial_light: init.as_deref(),
        // The light after the plan's last slab is what the callers read.
        every_slab: true,
        ..SweepOptions::default()
    };
    let t = std::time::Instant::now();
    let out = sweep(&plan, &g.raster, &ldi, &options).unwrap_or_else(|e| panic!("{e}"));
    (plan, out, t.elapsed().as_secs_f64())
}

/// Light channel 0 of light 0 at grid pixel (x, y) after the last slab.
pub fn light_at(plan: &RenderPlan, out: &SweepOutput, x: usize, y: usize) -> f64 {
    f64::from(out.light[y * plan.light_row_len() + x])
}

/// The light profile across the edge, averaged over 16 middle rows (away from the top and
/// bottom borders, where reads outside the buffer see unoccluded light).
pub fn edge_profile(plan: &RenderPlan, out: &SweepOutput) -> Vec<f64> {
    let mid = plan.grid_height as usize / 2;
    let rows = mid.saturating_sub(8)..(mid + 8).min(plan.grid_height as usize);
    (0..plan.grid_width as usize)
        .map(|x| rows.clone().map(|y| light_at(plan, out, x, y)).sum::<f64>() / rows.len() as f64)
        .collect()
}

/// Where a profile sampled at pixel centres (column x at x + 0.5) first rises through `level`,
/// searching from column `from`; linear interpolation between the two columns. `None` if never.
pub fn crossing(profile: &[f64], level: f64, from: usize) -> Option<f64> {
    for x in from.max(1)..profile.len() {
        if profile[x - 1] < level && profile[x] >= level {
            let t = (level - profile[x - 1]) / (profile[x] - profile[x - 1]);
            return Some(x as f64 - 0.5 + t);
        }
    }
    None
}

/// The half-shadow isoline: where the profile first rises through 0.5 from column `from`.
pub fn half_crossing(profile: &[f64], from: usize) -> Option<f64> {
    crossing(profile, 0.5, from)
}

/// The 10–90 % penumbra width (px): distance between the 0.1 and 0.9 crossings.
pub fn width_10_90(profile: &[f64], from: usize) -> Option<f64> {
    Some(crossing(profile, 0.9, from)? - crossing(profile, 0.1, from)?)
}

/// The edge's light at pixel centres for a Gaussian penumbra of standard deviation `std` px
/// centred on `center` (a Heaviside step when `std` is 0): the correct shadow (std d·σ/px) or
/// the iterated model (std √(d·d1)·σ/px, paper eq. 8).
pub fn model_profile(len: usize, center: f64, std: f64) -> Vec<f64> {
    (0..len)
        .map(|x| {
            let u = x as f64 + 0.5 - center;
            if std > 0.0 {
                phi(u / std)
            } else if u > 0.0 {
                1.0
            } else if u < 0.0 {
                0.0
            } else {
                0.5
            }
        })
        .collect()
}

/// The standard normal CDF Φ (to about 1e-15; see `convshadow_reference::normal_cdf`).
pub fn phi(x: f64) -> f64 {
    crate::normal_cdf(x)
}
