//! The speed-vs-error plot (plotters, bitmap backend into a buffer, PNG by `image`).
//!
//! Text needs a font: plotters' `ab_glyph` feature loads none by itself, so a TrueType font is
//! registered at run time from `CONVSHADOW_FONT` or the usual system paths (DejaVu Sans,
//! Liberation Sans, FreeSans). Without one the plot is drawn without any text (axes, lines and
//! points only) and [`draw`] says so, instead of failing.

use std::path::Path;
use std::sync::OnceLock;

use plotters::prelude::*;

use super::grid::kernels;
use super::row::{Row, mean};

/// One kernel's points: (time per frame in ms, error, slab count).
#[derive(Clone, Debug)]
pub struct Series {
    /// Kernel name (the legend).
    pub name: String,
    /// Points, in slab-count order.
    pub points: Vec<(f64, f64, u32)>,
}

/// One panel: title, y-axis description and its series.
#[derive(Clone, Debug)]
pub struct Panel {
    /// Panel title.
    pub title: String,
    /// Y axis description.
    pub y_desc: String,
    /// Series (one per kernel).
    pub series: Vec<Series>,
}

const FONT_PATHS: [&str; 4] = [
    "/usr/share/fonts/truetype/dejavu/DejaVuSans.ttf",
    "/usr/share/fonts/truetype/liberation/LiberationSans-Regular.ttf",
    "/usr/share/fonts/truetype/freefont/FreeSans.ttf",
    "/System/Library/Fonts/Supplemental/Arial.ttf",
];

/// Registers a font for plotters once; returns whether text can be drawn.
pub fn font_available() -> bool {
    static FONT: OnceLock<bool> = OnceLock::new();
    *FONT.get_or_init(|| {
        let candidates = std::env::var("CONVSHADOW_FONT")
            .ok()
            .into_iter()
            .chain(FONT_PATHS.iter().map(|s| s.to_string()));
        for path in candidates {
            if let Ok(bytes) = std::fs::read(&path) {
                let bytes: &'static [u8] = Box::leak(bytes.into_boxed_slice());
                if plotters::style::register_font("sans-serif", FontStyle::Normal, bytes).is_ok() {
                    return true;
                }
            }
        }
        false
    })
}

/// Draws the panels side by side (log–log: time per frame against error) into a PNG.
/// Returns whether text (titles, axes, legend, slab labels) was drawn.
pub fn draw(path: &Path, panels: &[Panel]) -> Result<bool, String> {
    let text = font_available();
    let (w, h) = (620 * panels.len().max(1) as u32, 560u32);
    let mut buf = vec![0u8; (w * h * 3) as usize];
    {
        let root = BitMapBackend::with_buffer(&mut buf, (w, h)).into_drawing_area();
        root.fill(&WHITE).map_err(|e| e.to_string())?;
        let areas = root.split_evenly((1, panels.len().max(1)));
        for (area, panel) in areas.iter().zip(panels) {
            draw_panel(area, panel, text).map_err(|e| e.to_string())?;
        }
        root.present().map_err(|e| e.to_string())?;
    }
    // Written to a temporary file and renamed, like every output.
    convshadow_io::image::save_rgb8_png(path, w, h, buf).map_err(|e| e.to_string())?;
    Ok(text)
}

/// A pixel rectangle (left, top, right, bottom).
type Rect = (i32, i32, i32, i32);

/// Candidate label offsets from a point (right, left, above, below): the first whose box is free
/// is taken and added to `taken`.
fn free_offset(taken: &mut Vec<Rect>, (x, y): (i32, i32), chars: usize) -> Option<(i32, i32)> {
    let (w, h) = (7 * chars as i32 + 2, 12);
    let candidates = [
        (7, -6),
        (-7 - w, -6),
        (6, -h - 4),
        (6, 4),
        (-w - 6, -h - 4),
        (-w - 6, 4),
        (-w / 2, -h - 7),
        (-w / 2, 7),
    ];
    let overlaps = |a: &Rect, b: &Rect| a.0 < b.2 && b.0 < a.2 && a.1 < b.3 && b.1 < a.3;
    for (dx, dy) in candidates {
        let r = (x + dx, y + dy, x + dx + w, y + dy + h);
        if !taken.iter().any(|t| overlaps(t, &r)) {
            taken.push(r);
            return Some((dx, dy));
        }
    }
    None
}

/// A log axis' tick label: only at 1, 2 and 5 times a power of ten (the others stay unlabelled,
/// so the labels of a decade's upper ticks do not run into each other), printed without float
/// noise (0.002, not 0.0020000000000000005).
fn log_tick(v: &f64) -> String {
    if !(v.is_finite() && *v > 0.0) {
        return String::new();
    }
    let e = v.log10().floor();
    let m = v / 10f64.powf(e);
    // The key points of a log axis can land a hair either side of the mantissa.
    let m = if m > 9.999 { 1.0 } else { m };
    let e = if v / 10f64.powf(e) > 9.999 {
        e + 1.0
    } else {
        e
    };
    if ![1.0, 2.0, 5.0].iter().any(|k| (m - k).abs() < 1e-3) {
        return String::new();
    }
    let decimals = if e < 0.0 { (-e) as usize } else { 0 };
    format!("{:.*}", decimals, m.round() * 10f64.powf(e))
}

type Area<'a> = DrawingArea<BitMapBackend<'a>, plotters::coord::Shift>;

fn draw_panel(
    area: &Area<'_>,
    panel: &Panel,
    text: bool,
) -> Result<(), Box<dyn std::error::Error + 'static>> {
    let pts = panel.series.iter().flat_map(|s| s.points.iter());
    let (mut x0, mut x1, mut y0, mut y1) = (f64::INFINITY, 0.0f64, f64::INFINITY, 0.0f64);
    for p in pts {
        x0 = x0.min(p.0);
        x1 = x1.max(p.0);
        y0 = y0.min(p.1.max(1e-6));
        y1 = y1.max(p.1.max(1e-6));
    }
    if !x0.is_finite() || !y0.is_finite() {
        (x0, x1, y0, y1) = (1.0, 10.0, 1e-3, 1.0);
    }
    // From the decade below the fastest point, so that the log axis labels a power of ten there.
    let (x0, x1) = (10f64.powf((x0 / 1.3).log10().floor()), x1 * 1.3);
    let (mut y0, mut y1) = (y0 / 1.5, y1 * 1.5);
    // At least a decade, so that the log axis has labelled ticks.
    if y1 / y0 < 10.0 {
        let grow = (10.0 * y0 / y1).sqrt();
        y0 /= grow;
        y1 *= grow;
    }
    let mut builder = ChartBuilder::on(area);
    builder.margin(12);
    if text {
        builder
            .caption(&panel.title, ("sans-serif", 18))
            .x_label_area_size(42)
            .y_label_area_size(62);
    } else {
        builder.x_label_area_size(4).y_label_area_size(4);
    }
    let mut chart = builder.build_cartesian_2d((x0..x1).log_scale(), (y0..y1).log_scale())?;
    if text {
        chart
            .configure_mesh()
            .x_desc("time per frame (ms)")
            .y_desc(panel.y_desc.as_str())
            .x_labels(12)
            .y_labels(12)
            .x_label_formatter(&log_tick)
            .y_label_formatter(&log_tick)
            .label_style(("sans-serif", 13))
            .draw()?;
    } else {
        chart
            .configure_mesh()
            .x_labels(0)
            .y_labels(0)
            .disable_x_mesh()
            .disable_y_mesh()
            .draw()?;
    }
    for (i, s) in panel.series.iter().enumerate() {
        let color = Palette99::pick(i).to_rgba();
        let line: Vec<(f64, f64)> = s.points.iter().map(|p| (p.0, p.1.max(1e-6))).collect();
        let drawn = chart.draw_series(LineSeries::new(line.clone(), color.stroke_width(2)))?;
        if text {
            drawn.label(s.name.as_str()).legend(move |(x, y)| {
                PathElement::new(vec![(x, y), (x + 18, y)], color.stroke_width(2))
            });
        }
        chart.draw_series(line.iter().map(|&p| Circle::new(p, 4, color.filled())))?;
    }
    if text {
        // Slab-count labels beside their points, each where it overlaps no point and no other
        // label (in pixels); a label with no free place is left out rather than drawn over one.
        let at = |p: &(f64, f64, u32)| (p.0, p.1.max(1e-6));
        let mut taken: Vec<Rect> = panel
            .series
            .iter()
            .flat_map(|s| s.points.iter())
            .map(|p| {
                let (x, y) = chart.backend_coord(&at(p));
                (x - 5, y - 5, x + 5, y + 5)
            })
            .collect();
        let mut labels = Vec::new();
        for p in panel.series.iter().flat_map(|s| s.points.iter()) {
            let label = p.2.to_string();
            let (x, y) = chart.backend_coord(&at(p));
            if let Some(offset) = free_offset(&mut taken, (x, y), label.len()) {
                labels.push((at(p), label, offset));
            }
        }
        chart.draw_series(labels.into_iter().map(|(p, label, offset)| {
            EmptyElement::at(p)
                + Text::new(label, offset, ("sans-serif", 11).into_font().color(&BLACK))
        }))?;
    }
    if text {
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.85))
            .border_style(BLACK)
            .label_font(("sans-serif", 12))
            .draw()?;
    }
    Ok(())
}

/// Per (kernel, penumbra, slabs): mean time and mean of `err` over the rows selected by `keep`;
/// one series per kernel and penumbra model present (`ellipse2 (distance)`).
fn aggregate(
    rows: &[Row],
    keep: &dyn Fn(&Row) -> bool,
    err: &dyn Fn(&Row) -> Option<f64>,
) -> Vec<Series> {
    let penumbras: Vec<&str> = ["iterated", "distance"]
        .into_iter()
        .filter(|p| rows.iter().any(|r| r.penumbra == *p))
        .collect();
    let both = penumbras.len() > 1;
    kernels()
        .flat_map(|k| penumbras.iter().map(move |p| (k, *p)))
        .map(|(k, p)| {
            let keep = |r: &Row| r.penumbra == p && keep(r);
            let mut slabs: Vec<u32> = rows
                .iter()
                .filter(|r| r.kernel == *k && keep(r))
                .map(|r| r.slabs)
                .collect();
            slabs.sort_unstable();
            slabs.dedup();
            let points = slabs
                .iter()
                .filter_map(|&n| {
                    let sel: Vec<&Row> = rows
                        .iter()
                        .filter(|r| r.kernel == *k && r.slabs == n && keep(r))
                        .collect();
                    let t = mean(sel.iter().map(|r| r.time_ms));
                    let e = mean(sel.iter().filter_map(|r| err(r)));
                    (t.is_finite() && e.is_finite()).then_some((t, e, n))
                })
                .collect();
            Series {
                name: if both {
                    format!("{k} ({p})")
                } else {
                    k.to_string()
                },
                points,
            }
        })
        .collect()
}

/// The narrow-band family's series: `ellipse2` without and with pre-integration.
fn narrowband_series(rows: &[Row]) -> Vec<Series> {
    [(false, "ellipse2"), (true, "ellipse2 + pre-integration")]
        .into_iter()
        .map(|(pre, name)| Series {
            name: name.to_string(),
            points: rows
                .iter()
                .filter(|r| r.family == "narrowband" && r.preintegration == pre)
                .filter_map(|r| Some((r.time_ms, r.rmse_reference?, r.slabs)))
                .filter(|(t, e, _)| t.is_finite() && e.is_finite())
                .collect(),
        })
        .collect()
}

/// The figure's panels: edge against both references, the scene against shadow rays, and (when
/// the report ran it) the narrow-band scene with and without pre-integration.
pub fn panels(rows: &[Row]) -> Vec<Panel> {
    let edge_on = |r: &Row| r.family == "edge" && r.compensation;
    let mut out = vec![
        Panel {
            title: "edge: error vs the correct shadow".into(),
            y_desc: "mean RMSE (light)".into(),
            series: aggregate(rows, &edge_on, &|r| r.rmse_correct),
        },
        Panel {
            title: "edge: error vs the iterated model".into(),
            y_desc: "mean RMSE (light)".into(),
            series: aggregate(rows, &edge_on, &|r| r.rmse_iterated),
        },
        Panel {
            title: "default scene vs shadow-ray reference".into(),
            y_desc: "image RMSE (linear)".into(),
            series: aggregate(rows, &|r| r.family == "scene", &|r| r.rmse_reference),
        },
    ];
    if rows.iter().any(|r| r.family == "narrowband") {
        out.push(Panel {
            title: "narrow band vs 2048 slabs: pre-integration".into(),
            y_desc: "image RMSE (linear)".into(),
            series: narrowband_series(rows),
        });
    }
    out
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn log_ticks_label_one_two_five_only() {
        assert_eq!(log_tick(&100.0), "100");
        assert_eq!(log_tick(&20.000000000000004), "20");
        assert_eq!(log_tick(&0.0020000000000000005), "0.002");
        assert_eq!(log_tick(&0.049999999999), "0.05");
        assert_eq!(log_tick(&0.0999999999), "0.1");
        assert_eq!(log_tick(&80.0), "");
        assert_eq!(log_tick(&0.03), "");
    }

    #[test]
    fn labels_take_free_places_or_none() {
        let mut taken = vec![(0, 0, 10, 10)];
        // Right of a point far away: the first candidate.
        assert_eq!(free_offset(&mut taken, (100, 100), 2), Some((7, -6)));
        // The same point again: the right is taken now, so the left.
        assert_eq!(free_offset(&mut taken, (100, 100), 2), Some((-7 - 16, -6)));
        // Surrounded: no place at all.
        let mut full = vec![(-1000, -1000, 1000, 1000)];
        assert_eq!(free_offset(&mut full, (0, 0), 3), None);
    }
}
