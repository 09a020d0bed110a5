//! `report.md`: the tables of the report.

use std::fmt::Write as _;

use super::grid::{NARROWBAND_REFERENCE_SLABS, ReportOptions, TILTS, kernels};
use super::row::{Report, Row, mean};

fn fmt(v: f64) -> String {
    if v.is_nan() {
        "–".into()
    } else if v.abs() >= 100.0 {
        format!("{v:.0}")
    } else if v.abs() >= 0.01 || v == 0.0 {
        format!("{v:.3}")
    } else {
        format!("{v:.1e}")
    }
}

fn max_abs(v: impl Iterator<Item = f64>) -> f64 {
    v.fold(f64::NAN, |m, x| {
        if m.is_nan() || x.abs() > m {
            x.abs()
        } else {
            m
        }
    })
}

/// The machine: `nproc` and the CPU model from /proc/cpuinfo.
pub fn machine() -> String {
    let cpus = std::thread::available_parallelism().map_or(1, |n| n.get());
    let model = std::fs::read_to_string("/proc/cpuinfo")
        .ok()
        .and_then(|s| {
            s.lines()
                .find(|l| l.starts_with("model name"))
                .and_then(|l| l.split(':').nth(1))
                .map(|m| m.trim().to_string())
        })
        .unwrap_or_else(|| "unknown CPU".to_string());
    format!("{cpus} logical CPUs (nproc), {model}")
}

/// The text of `report.md`.
pub fn markdown(report: &Report, options: &ReportOptions) -> String {
    let mut md = String::new();
    let _ = writeln!(md, "# convshadow speed-against-error report\n");
    let _ = writeln!(
        md,
        "Machine: {}. Report time {:.0} s. Cases: {}.\n",
        machine(),
        report.seconds,
        options.describe()
    );
    let _ = writeln!(
        md,
        "Times are the sweep's wall time for one frame (edge 384×64, disk 256×192, scene as \
         given) on all cores; they are noisy when the machine is shared. Light values are in \
         [0, 1]. Every number is in `report.csv`.\n"
    );
    if !report.plot_text {
        let _ = writeln!(
            md,
            "Note: no TrueType font was found, so `speed_vs_error.png` has no text \
             (set CONVSHADOW_FONT to a .ttf file).\n"
        );
    }
    edge_table(&mut md, &report.rows);
    over_blur_table(&mut md, &report.rows);
    growth_table(&mut md, &report.rows);
    disk_table(&mut md, &report.rows);
    scene_table(&mut md, &report.rows);
    narrowband_table(&mut md, &report.rows);
    direction_table(&mut md, &report.rows);
    perspective_table(&mut md, &report.rows);
    point_table(&mut md, &report.rows);
    md
}

/// The point-light family: time and error per camera and light-grid resolution.
fn point_table(md: &mut String, rows: &[Row]) {
    let rows: Vec<&Row> = rows.iter().filter(|r| r.family == "point").collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "\n## A point light\n\nA point light of radius 0.1 two units before an opaque thin \
         half-plane, its penumbra on a Lambert wall one unit behind \
         (`convshadow_reference::point_edge`); the light swept on its own grid, a perspective \
         view from its centre, the distance penumbra in its φ (how-it-works.md, \"The sweep's \
         point lights\"). RMSE over the wall, normalised by the unshadowed light, against the \
         visibility integrated over the light's Gaussian. Issue 41 asks ≤ 5·10⁻³; the light \
         resolution (cells per eye pixel) is the speed-against-error axis: the edge's \
         rasterization on the light's grid is the error left.\n"
    );
    let _ = writeln!(
        md,
        "| camera | light resolution | slabs | time ms | RMSE vs correct |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|");
    for r in &rows {
        let camera = match r.fov_deg {
            Some(fov) => format!("perspective {fov}°"),
            None => "orthographic".to_string(),
        };
        let _ = writeln!(
            md,
            "| {camera} | {} | {} | {} | {} |",
            r.light_resolution.unwrap_or(f64::NAN),
            r.slabs,
            fmt(r.time_ms),
            fmt(r.rmse_correct.unwrap_or(f64::NAN)),
        );
    }
}

/// The perspective family: time and error per field of view and penumbra model.
fn perspective_table(md: &mut String, rows: &[Row]) {
    let rows: Vec<&Row> = rows.iter().filter(|r| r.family == "perspective").collect();
    if rows.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "\n## A perspective camera\n\nAn opaque half-plane 0.5 before a receiver, a Gaussian light \
         along the view, the eye off to the side (`convshadow_reference::perspective_edge`); the \
         light swept on the slab grid, the eye's rays reading it (how-it-works.md, \"A \
         perspective camera\"). RMSE over the receiver against the closed form where each \
         pixel's ray meets it; the half-shadow line's largest offset from the projected \
         geometric line. Issue 42 asks ≤ 5·10⁻³ and 0.5 px. The light resolution \
         (`sweep.light_resolution`) is the light grid's cells per eye pixel: a speed-against-error \
         axis, shown with the edge on the default grid's pixel boundaries and 0.3 of its pixels \
         off them (where the grid's LDI quantises it, issue 46).\n"
    );
    let _ = writeln!(
        md,
        "| fov | penumbra | light resolution | edge | slabs | time ms | RMSE vs correct | line offset px |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    for r in &rows {
        let _ = writeln!(
            md,
            "| {}° | {} | {} | {} | {} | {} | {} | {} |",
            r.fov_deg.unwrap_or(f64::NAN),
            r.penumbra,
            r.light_resolution.unwrap_or(f64::NAN),
            r.variance_level,
            r.slabs,
            fmt(r.time_ms),
            fmt(r.rmse_correct.unwrap_or(f64::NAN)),
            fmt(r.isoline_err_px.unwrap_or(f64::NAN)),
        );
    }
}

/// The light-direction family: time and error per light, angle and penumbra model, and each
/// angle's time over the same light's and model's at 0°.
fn direction_table(md: &mut String, rows: &[Row]) {
    let dir: Vec<&Row> = rows.iter().filter(|r| r.family == "direction").collect();
    if dir.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "\n## Lights from any direction\n\nAn opaque thin half-plane over a translucent sheet, \
         both perpendicular to a Gaussian directional light, the camera at an angle from the \
         light's travel (`convshadow_reference::half_plane_sheet`); RMSE of the sheet's profile, \
         normalised by its lit level, against the closed form along each view ray. Above 90° \
         the light is swept in a second pass from the far end. Light `point`: a soft point light \
         on the axis instead (radius 0.05 of its distance, which is the nearest the sweep allows \
         at each angle; its grid at half the eye's resolution at 80° and 100°), against the \
         visibility integrated over its Gaussian, each pixel over its own unshadowed light. \
         Issue 41 asks ≤ 5·10⁻³ at every angle and at most 2× the 0° time at 100°.\n"
    );
    let _ = writeln!(
        md,
        "| light | angle | penumbra | slabs | time ms | time / 0° | RMSE vs correct |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    for r in &dir {
        let at_zero = dir
            .iter()
            .find(|z| {
                z.view_angle_deg == Some(0.0)
                    && z.variance_level == r.variance_level
                    && z.penumbra == r.penumbra
            })
            .map_or(f64::NAN, |z| r.time_ms / z.time_ms);
        let _ = writeln!(
            md,
            "| {} | {}° | {} | {} | {} | {} | {} |",
            r.variance_level,
            r.view_angle_deg.unwrap_or(f64::NAN),
            r.penumbra,
            r.slabs,
            fmt(r.time_ms),
            fmt(at_zero),
            fmt(r.rmse_correct.unwrap_or(f64::NAN)),
        );
    }
}

/// The penumbra models present in `rows`, iterated first.
fn penumbras(rows: &[Row]) -> Vec<&'static str> {
    ["iterated", "distance"]
        .into_iter()
        .filter(|p| rows.iter().any(|r| r.penumbra == *p))
        .collect()
}

/// The narrow-band scene with and without pre-integrated compositing.
fn narrowband_table(md: &mut String, rows: &[Row]) {
    let nb: Vec<&Row> = rows.iter().filter(|r| r.family == "narrowband").collect();
    if nb.is_empty() {
        return;
    }
    let _ = writeln!(
        md,
        "\n## Narrow band: pre-integrated compositing\n\n`scenes/narrowband.toml` (an opacity \
         band 0.05 wide over fBm), `ellipse2`, against its {}-slab sweep without \
         pre-integration.\n",
        NARROWBAND_REFERENCE_SLABS
    );
    let _ = writeln!(
        md,
        "| slabs | size | pre-integration | time ms | image RMSE vs reference | reference self-error |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for r in nb {
        let _ = writeln!(
            md,
            "| {} | {}×{} | {} | {} | {} | {} |",
            r.slabs,
            r.width,
            r.height,
            if r.preintegration { "on" } else { "off" },
            fmt(r.time_ms),
            fmt(r.rmse_reference.unwrap_or(f64::NAN)),
            fmt(r.reference_self_err.unwrap_or(f64::NAN)),
        );
    }
}

/// Edge cases with compensation on, per kernel × slab count.
fn edge_table(md: &mut String, rows: &[Row]) {
    let _ = writeln!(
        md,
        "## Edge (compensation on): mean over distances, variances and tilts\n"
    );
    let _ = writeln!(
        md,
        "| kernel | penumbra | slabs | time ms | RMSE vs correct | RMSE vs iterated | max abs isoline err px | max abs 10–90 width err vs iterated px |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|---|");
    for (k, p) in kernels().flat_map(|k| penumbras(rows).into_iter().map(move |p| (k, p))) {
        let mut ns: Vec<u32> = rows
            .iter()
            .filter(|r| r.family == "edge")
            .map(|r| r.slabs)
            .collect();
        ns.sort_unstable();
        ns.dedup();
        for n in ns {
            let sel: Vec<&Row> = rows
                .iter()
                .filter(|r| {
                    r.family == "edge"
                        && r.compensation
                        && r.kernel == k
                        && r.penumbra == p
                        && r.slabs == n
                })
                .collect();
            if sel.is_empty() {
                continue;
            }
            let _ = writeln!(
                md,
                "| {k} | {p} | {n} | {} | {} | {} | {} | {} |",
                fmt(mean(sel.iter().map(|r| r.time_ms))),
                fmt(mean(sel.iter().filter_map(|r| r.rmse_correct))),
                fmt(mean(sel.iter().filter_map(|r| r.rmse_iterated))),
                fmt(max_abs(sel.iter().filter_map(|r| r.isoline_err_px))),
                fmt(max_abs(sel.iter().filter_map(|r| r.width_err_iterated_px))),
            );
        }
    }
}

/// Zero-variance penumbra widths, compensation on and off.
fn over_blur_table(md: &mut String, rows: &[Row]) {
    let _ = writeln!(
        md,
        "\n## Over-blur: zero-variance light, measured 10–90 % width (px; a sampled step measures 0.8)\n"
    );
    let _ = writeln!(
        md,
        "| kernel | penumbra | compensation | tilt | max width px | mean RMSE vs iterated, all variances |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|");
    for (k, p) in kernels().flat_map(|k| penumbras(rows).into_iter().map(move |p| (k, p))) {
        for comp in [true, false] {
            for tilt in TILTS {
                let sel: Vec<&Row> = rows
                    .iter()
                    .filter(|r| {
                        r.family == "edge"
                            && r.kernel == k
                            && r.penumbra == p
                            && r.compensation == comp
                            && r.tilt_deg == Some(tilt)
                    })
                    .collect();
                if sel.is_empty() {
                    continue;
                }
                let zero = max_abs(
                    sel.iter()
                        .filter(|r| r.variance_level == "zero")
                        .filter_map(|r| r.width_px),
                );
                let _ = writeln!(
                    md,
                    "| {k} | {p} | {} | {tilt}° | {} | {} |",
                    if comp { "on" } else { "off" },
                    fmt(zero),
                    fmt(mean(sel.iter().filter_map(|r| r.rmse_iterated))),
                );
            }
        }
    }
}

/// The √d growth of the penumbra: ellipse2 against both references per distance.
fn growth_table(md: &mut String, rows: &[Row]) {
    let _ = writeln!(
        md,
        "\n## Penumbra growth (paper §6): edge, ellipse2, compensation on, high variance\n"
    );
    let _ = writeln!(
        md,
        "| penumbra | d / d1 | slabs | RMSE vs correct | RMSE vs iterated | width err vs correct px | width err vs iterated px |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    for r in rows.iter().filter(|r| {
        r.family == "edge"
            && r.kernel == "ellipse2"
            && r.compensation
            && r.variance_level == "high"
            && r.tilt_deg == Some(45.0)
    }) {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {} | {} | {} | {} |",
            r.penumbra,
            fmt(r.distance_over_d1.unwrap_or(f64::NAN)),
            r.slabs,
            fmt(r.rmse_correct.unwrap_or(f64::NAN)),
            fmt(r.rmse_iterated.unwrap_or(f64::NAN)),
            fmt(r.width_err_correct_px.unwrap_or(f64::NAN)),
            fmt(r.width_err_iterated_px.unwrap_or(f64::NAN)),
        );
    }
}

/// The disk over a plane, per kernel.
fn disk_table(md: &mut String, rows: &[Row]) {
    let _ = writeln!(
        md,
        "\n## Disk over a plane: mean over its cases per kernel\n"
    );
    let _ = writeln!(
        md,
        "| kernel | penumbra | time ms | RMSE vs correct | RMSE vs iterated | mean isoline displacement px | width err vs iterated px |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    for (k, p) in kernels().flat_map(|k| penumbras(rows).into_iter().map(move |p| (k, p))) {
        let sel: Vec<&Row> = rows
            .iter()
            .filter(|r| r.family == "disk" && r.kernel == k && r.penumbra == p)
            .collect();
        if sel.is_empty() {
            continue;
        }
        let _ = writeln!(
            md,
            "| {k} | {p} | {} | {} | {} | {} | {} |",
            fmt(mean(sel.iter().map(|r| r.time_ms))),
            fmt(mean(sel.iter().filter_map(|r| r.rmse_correct))),
            fmt(mean(sel.iter().filter_map(|r| r.rmse_iterated))),
            fmt(mean(sel.iter().filter_map(|r| r.isoline_err_px))),
            fmt(mean(sel.iter().filter_map(|r| r.width_err_iterated_px))),
        );
    }
}

/// The default scene against the shadow-ray reference.
fn scene_table(md: &mut String, rows: &[Row]) {
    let _ = writeln!(md, "\n## Default scene against the shadow-ray reference\n");
    let _ = writeln!(
        md,
        "| kernel | penumbra | slabs | size | time ms | image RMSE vs reference | reference self-error (M vs 4M) |"
    );
    let _ = writeln!(md, "|---|---|---|---|---|---|---|");
    for r in rows.iter().filter(|r| r.family == "scene") {
        let _ = writeln!(
            md,
            "| {} | {} | {} | {}×{} | {} | {} | {} |",
            r.kernel,
            r.penumbra,
            r.slabs,
            r.width,
            r.height,
            fmt(r.time_ms),
            fmt(r.rmse_reference.unwrap_or(f64::NAN)),
            fmt(r.reference_self_err.unwrap_or(f64::NAN)),
        );
    }
    if rows.iter().any(|r| r.family == "scene") {
        let _ = writeln!(
            md,
            "\nThe image RMSE is against the 4·M reference. The self-error is the M run's \
             difference from it, an estimate of the M run's own error; the 4·M run's is smaller \
             still (its error falls at least 1.6× each time M quadruples: \
             `tests/accuracy/hard_cases.rs`)."
        );
    }
}
