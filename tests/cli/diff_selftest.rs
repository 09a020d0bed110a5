//! `convshadow diff` sees a known injected difference in every metric, and reports zero error for
//! identical images (a diff tool that compares an image with itself must not pass everything).

use crate::support;

use convshadow::io::image::RgbImage;

/// A smooth test image with some structure.
fn test_image(w: u32, h: u32) -> RgbImage {
    let mut data = Vec::new();
    for y in 0..h {
        for x in 0..w {
            let u = x as f32 / w as f32;
            let v = y as f32 / h as f32;
            data.extend([u * 0.8, v * 0.6 + 0.1, (u * v) * 0.5 + 0.2]);
        }
    }
    RgbImage {
        width: w,
        height: h,
        data,
    }
}

fn diff(dir: &std::path::Path, a: &str, b: &str) -> serde_json::Value {
    let (code, out, err) = support::run_cli(
        &["diff", a, b, "--json", "d.json", "--heatmap", "heat.png"],
        dir,
    );
    assert_eq!(code, 0, "{out}{err}");
    assert!(out.contains("max abs error"), "{out}");
    serde_json::from_str(&std::fs::read_to_string(dir.join("d.json")).unwrap()).unwrap()
}

#[test]
fn diff_sees_an_injected_difference_in_every_metric() {
    let dir = support::temp_dir("diff-selftest");
    let (w, h) = (64u32, 48u32);
    let a = test_image(w, h);
    a.save(&dir.join("a.exr")).unwrap();
    a.save(&dir.join("a_copy.exr")).unwrap();

    // Identical images: every error is zero, the heat-map is black.
    let same = diff(&dir, "a.exr", "a_copy.exr");
    assert_eq!(same["max_abs_error"], 0.0);
    assert_eq!(same["rmse"], 0.0);
    assert!(same["psnr_db"].is_null(), "infinite PSNR is null: {same}");
    assert_eq!(same["mean_flip"], 0.0);
    assert_eq!(same["srgb8_pixels_differ"], 0);
    assert_eq!(same["srgb8_max_diff"], 0);
    assert_eq!(same["bit_identical"], true);
    let heat = image::open(dir.join("heat.png")).unwrap().to_rgb8();
    assert!(heat.pixels().all(|p| p.0 == [0, 0, 0]));

    // Inject: a bright 3×3 block (+0.3 in red) and one value one ULP off.
    let mut b = a.clone();
    for y in 20..23 {
        for x in 30..33 {
            b.data[((y * w + x) * 3) as usize] += 0.3;
        }
    }
    let ulp_at = ((5 * w + 7) * 3 + 2) as usize;
    b.data[ulp_at] = f32::from_bits(b.data[ulp_at].to_bits() + 1);
    b.save(&dir.join("b.exr")).unwrap();
    let d = diff(&dir, "a.exr", "b.exr");
    let max_abs = d["max_abs_error"].as_f64().unwrap();
    assert!((max_abs - 0.3).abs() < 1e-6, "{d}");
    let at = d["max_abs_error_at"].as_array().unwrap();
    assert!(
        (30..33).contains(&at[0].as_u64().unwrap()) && (20..23).contains(&at[1].as_u64().unwrap())
    );
    assert_eq!(at[2], 0, "the red channel");
    let expect_rmse = (9.0f64 * 0.09 / f64::from(w * h * 3)).sqrt();
    let rmse = d["rmse"].as_f64().unwrap();
    assert!(
        (rmse - expect_rmse).abs() < 1e-4 * expect_rmse,
        "{rmse} vs {expect_rmse}"
    );
    let psnr = d["psnr_db"].as_f64().unwrap();
    assert!((psnr + 20.0 * expect_rmse.log10()).abs() < 1e-3, "{psnr}");
    assert!(
        d["mean_flip"].as_f64().unwrap() > 0.0,
        "FLIP sees the block: {d}"
    );
    assert_eq!(d["srgb8_pixels_differ"], 9, "the block, not the ULP: {d}");
    assert!(d["srgb8_max_diff"].as_u64().unwrap() >= 40, "{d}");
    assert_eq!(d["values_differ"], 10);
    assert_eq!(d["bit_identical"], false);
    let ulps = d["ulp_histogram"].as_array().unwrap();
    assert_eq!(ulps[1][1], 1, "one value one ULP apart: {d}");
    let heat = image::open(dir.join("heat.png")).unwrap().to_rgb8();
    let (wx, wy) = (
        at[0].as_u64().unwrap() as u32,
        at[1].as_u64().unwrap() as u32,
    );
    assert_eq!(
        heat.get_pixel(wx, wy).0,
        [255, 255, 255],
        "the worst pixel is white"
    );
    for y in 20..23 {
        for x in 30..33 {
            let p = heat.get_pixel(x, y).0;
            assert!(
                p[0] == 255 && p[1] == 255 && p[2] > 200,
                "block pixel ({x}, {y}): {p:?}"
            );
        }
    }
    assert_ne!(heat.get_pixel(7, 5).0, [0, 0, 0], "a one-ULP pixel shows");
    assert_eq!(heat.get_pixel(0, 0).0, [0, 0, 0]);
    let lit = heat.pixels().filter(|p| p.0 != [0, 0, 0]).count();
    assert_eq!(lit, 10, "exactly the changed pixels are marked");

    // PNG inputs work too, and size mismatches are refused with the bad-input code.
    a.save(&dir.join("a.png")).unwrap();
    b.save(&dir.join("b.png")).unwrap();
    let d = diff(&dir, "a.png", "b.png");
    assert_eq!(d["srgb8_pixels_differ"], 9);
    test_image(32, 32).save(&dir.join("small.exr")).unwrap();
    let (code, _, err) = support::run_cli(&["diff", "a.exr", "small.exr"], &dir);
    assert_eq!(code, 3, "{err}");
    assert!(err.contains("differ in size"), "{err}");
}
