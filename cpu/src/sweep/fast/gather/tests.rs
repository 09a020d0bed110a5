use convshadow_common::model::kernel::KernelSpec;
use convshadow_common::pixel::lane::Lane;
use convshadow_common::plan::kernel::{
    KernelMoments, KernelTable, TableGuard, build_distance_table,
};
use convshadow_testkit::TestRng;
use wide::{f32x8, u32x8};

use super::*;
use crate::kernels::{LightTaps, OUTSIDE, OUTSIDE_DEPTH, TapOrigin, gather};
use crate::sweep::fast::per_lane::{LaneRows, TapColumns, gather_per_lane};

/// A distance-penumbra table of `kernel` for 40 slabs (levels of different widths).
fn distance_table(kernel: &str) -> KernelTable {
    let spec: KernelSpec = kernel.parse().expect("kernel");
    let per_e2 = |f: f64| KernelMoments {
        mean: [0.3 * f.sqrt(), -0.2],
        cov: [[0.35 * f, 0.1 * f], [0.1 * f, 0.2 * f]],
    };
    build_distance_table(spec, &per_e2, 40, true, &TableGuard::unlimited()).expect("unlimited")
}

/// A `w` × `h` light buffer of three channels and a depth plane per row (`4 · w` apart).
fn three_channels_and_depth(data: &[f32], w: usize, h: usize) -> LightPlanes<'_> {
    LightPlanes {
        data,
        base: 0,
        channels: 4,
        light_channels: 3,
        row_stride: 4 * w,
        pixel_step: 1,
        plane_step: w,
        width: w as i32,
        height: h as i32,
    }
}

#[test]
fn skipped_taps_are_zero_and_the_level_search_keeps_one_padding_tap() {
    for kernel in ["box", "gaussian:7", "ellipse2", "poisson8", "ellipse3:slab"] {
        let table = distance_table(kernel);
        let columns = TapColumns::new(&table, 1000, 1, 100);
        let padding = |t: &Tap| t.dx == 0 && t.dy == 0 && t.w == [0.0; 4];
        let mut padded_rows = 0;
        for row in 0..table.rows() {
            let taps = table.phase(row);
            let (g, l) = (
                columns.gather_taps[row as usize] as usize,
                columns.level_taps[row as usize] as usize,
            );
            assert!(
                g >= 1 && g <= taps.len() && l <= taps.len(),
                "{kernel} row {row}"
            );
            assert!(
                taps[g..].iter().all(|t| t.w == [0.0; 4]),
                "{kernel} row {row}"
            );
            assert!(taps[l..].iter().all(padding), "{kernel} row {row}");
            // The level search keeps every read corner: one padding tap stands for the rest.
            if taps.iter().any(padding) {
                assert!(taps[..l].iter().any(padding), "{kernel} row {row}");
            }
            padded_rows += usize::from(g < taps.len());
        }
        if kernel == "box" || kernel.starts_with("gaussian") {
            assert!(
                padded_rows > 0,
                "{kernel}: levels of different widths are padded"
            );
        }
    }
}

/// Eight rows of `table`: one row for every lane a third of the time, else each its own.
fn random_rows(rng: &mut TestRng, table: &KernelTable) -> [u32; 8] {
    let one_row = rng.below(3) == 0;
    let first = rng.below(table.rows());
    std::array::from_fn(|_| {
        if one_row {
            first
        } else {
            rng.below(table.rows())
        }
    })
}

#[test]
fn lane_rows_summarise_the_taps_of_every_lane() {
    // Against the taps themselves: the union of the lanes' extents, the most taps, uniformity.
    let mut rng = TestRng::new(3);
    for kernel in ["box", "gaussian:7", "ellipse2", "poisson8"] {
        let table = distance_table(kernel);
        let columns = TapColumns::new(&table, 1000, 1, 100);
        for _ in 0..200 {
            let rows = random_rows(&mut rng, &table);
            let got = LaneRows::of::<f32x8>(&columns, u32x8::new(rows));
            let taps = rows.map(|r| table.phase(r));
            let all = || taps.iter().flat_map(|t| t.iter());
            let extent = [
                all().map(|t| t.dx).min().unwrap(),
                all().map(|t| t.dx).max().unwrap(),
                all().map(|t| t.dy).min().unwrap(),
                all().map(|t| t.dy).max().unwrap(),
            ];
            assert_eq!(got.extent, extent, "{kernel} rows {rows:?}");
            // The offsets the gathers read (row stride 1000, as built above), as signed.
            let offsets = || all().map(|t| i64::from(t.dy) * 1000 + i64::from(t.dx));
            let span = [offsets().min().unwrap(), offsets().max().unwrap()];
            assert_eq!(got.offset_span, span, "{kernel} rows {rows:?}");
            let nonzero = |t: &[Tap]| t.iter().rposition(|t| t.w != [0.0; 4]).map_or(0, |i| i + 1);
            let most = taps.iter().map(|t| nonzero(t)).max().unwrap();
            assert_eq!(got.gather_taps, most, "{kernel} rows {rows:?}");
            let level_most = rows.map(|r| columns.level_taps[r as usize]);
            assert_eq!(got.level_taps, *level_most.iter().max().unwrap() as usize);
            let same = rows.iter().all(|&r| r == rows[0]);
            assert_eq!(
                got.uniform,
                same.then_some(rows[0]),
                "{kernel} rows {rows:?}"
            );
        }
    }
}

#[test]
fn a_summary_inside_the_grid_visits_the_taps_of_the_lanes_own() {
    // `within` against `of`: the same row and tap counts, extents and offset spans that hold
    // theirs; and `of` itself where the reads are not known to lie inside.
    let mut rng = TestRng::new(5);
    let mut fast = 0;
    for kernel in ["box", "gaussian:7", "ellipse2", "ellipse3:slab", "poisson8"] {
        let table = distance_table(kernel);
        let columns = TapColumns::new(&table, 1000, 1, 100);
        fast += usize::from(columns.same_counts);
        for _ in 0..200 {
            let rows = random_rows(&mut rng, &table);
            let rows = u32x8::new(rows);
            let own = LaneRows::of::<f32x8>(&columns, rows);
            for interior in [false, true] {
                let got = LaneRows::within::<f32x8>(&columns, rows, interior);
                let why = format!("{kernel} rows {rows:?} interior {interior}");
                assert_eq!(got.uniform, own.uniform, "{why}");
                assert_eq!(got.gather_taps, own.gather_taps, "{why}");
                assert_eq!(got.level_taps, own.level_taps, "{why}");
                let (e, o) = (got.extent, own.extent);
                let holds = e[0] <= o[0] && e[1] >= o[1] && e[2] <= o[2] && e[3] >= o[3];
                assert!(holds, "{why}");
                let (s, t) = (got.offset_span, own.offset_span);
                assert!(s[0] <= t[0] && s[1] >= t[1], "{why}");
                if !interior {
                    assert_eq!((e, s), (o, t), "{why}");
                }
            }
        }
    }
    // The default kernel's levels all visit the same taps: it takes the path without lookups.
    assert!(TapColumns::new(&distance_table("ellipse2"), 1000, 1, 100).same_counts);
    assert!(fast < 5, "the padded kernels keep the lookup per lane");
}

#[test]
#[should_panic(expected = "beyond the table")]
fn a_row_beyond_the_table_panics_without_a_lookup_too() {
    let table = distance_table("ellipse2");
    let columns = TapColumns::new(&table, 1000, 1, 100);
    LaneRows::within::<f32x8>(&columns, f32x8::u_splat(table.rows()), true);
}

#[test]
fn a_uniform_row_gathers_the_bits_of_the_per_lane_gather() {
    let (w, h) = (64usize, 40usize);
    let mut rng = TestRng::new(9);
    for kernel in ["box", "gaussian:7", "ellipse2:slab"] {
        let table = distance_table(kernel);
        // Three light channels and a depth plane per row.
        let row_stride = 4 * w;
        let data: Vec<f32> = (0..row_stride * h)
            .map(|_| rng.below(1 << 20) as f32 / (1 << 20) as f32)
            .collect();
        let columns = TapColumns::new(&table, row_stride, 1, w);
        let light_taps = LightTaps::new(&table);
        let skips_inside = (0..table.rows())
            .any(|r| light_taps.weighted(r).len() < columns.gather_taps[r as usize] as usize);
        // A box kernel's phases have zero taps between weighted ones: the skip is exercised.
        assert!(
            skips_inside || kernel != "box",
            "{kernel}: no zero tap to skip"
        );
        let planes = three_channels_and_depth(&data, w, h);
        for row in 0..table.rows() {
            for (x0, y) in [(20, 20), (0, 1), (w as i32 - 8, h as i32 - 2)] {
                let shift = [rng.below(3) as i32 - 1, rng.below(3) as i32 - 1];
                let (mut uniform, mut per_lane) = ([f32x8::splat(0.0); 4], [f32x8::splat(0.0); 4]);
                // The uniform gather skips zero taps; the per-lane one visits them all.
                let extent = columns.extent[row as usize];
                let taps = light_taps.weighted(row);
                let at = TapOrigin {
                    x: x0,
                    y,
                    shift,
                    inside: false,
                };
                gather_lanes(&planes, taps, extent, at, &mut uniform);
                let rows = f32x8::u_splat(row);
                let reads = LaneRows::of::<f32x8>(&columns, rows);
                gather_per_lane(&planes, &table, &columns, rows, &reads, at, &mut per_lane);
                for c in 0..4 {
                    let (a, b) = (uniform[c].to_array(), per_lane[c].to_array());
                    assert_eq!(
                        a.map(f32::to_bits),
                        b.map(f32::to_bits),
                        "{kernel} row {row} at ({x0}, {y}) plane {c}"
                    );
                }
            }
        }
    }
}

/// `planar` (`planes` planes per row, each `w` wide, rows `planes · w` apart) with its pixels
/// interleaved (pixel x's plane c at `x · planes + c`), and 8 floats of slack after it.
fn interleave(planar: &[f32], w: usize, planes: usize) -> Vec<f32> {
    let mut out = vec![f32::NAN; planar.len() + 8];
    for (k, &v) in planar.iter().enumerate() {
        let (row, at) = (k / (planes * w), k % (planes * w));
        let (c, x) = (at / w, at % w);
        out[row * planes * w + x * planes + c] = v;
    }
    out
}

#[test]
fn a_pixel_interleaved_buffer_gathers_the_bits_of_a_planar_one() {
    let (w, h) = (48usize, 40usize);
    let mut rng = TestRng::new(21);
    for kernel in ["ellipse2", "poisson8", "box", "gaussian:7", "ellipse2:slab"] {
        let table = distance_table(kernel);
        // Per case: the planes per pixel, the planes gathered (a depth plane alone: the
        // last) and the first of them.
        for (per_pixel, gathered, first) in [(4, 4, 0), (3, 3, 0), (2, 2, 0), (4, 1, 3)] {
            let row_stride = per_pixel * w;
            let planar: Vec<f32> = (0..row_stride * h + 8)
                .map(|_| rng.below(1 << 20) as f32 / (1 << 20) as f32)
                .collect();
            let pixels = interleave(&planar[..row_stride * h], w, per_pixel);
            let light = gathered.min(3 - first.min(3));
            let by_plane = LightPlanes {
                data: &planar,
                base: first * w,
                channels: gathered,
                light_channels: light,
                row_stride,
                pixel_step: 1,
                plane_step: w,
                width: w as i32,
                height: h as i32,
            };
            let by_pixel = LightPlanes {
                data: &pixels,
                base: first,
                pixel_step: per_pixel,
                plane_step: 1,
                ..by_plane
            };
            let planar_columns = TapColumns::new(&table, row_stride, 1, w);
            let pixel_columns = TapColumns::new(&table, row_stride, per_pixel, w);
            let light_taps = LightTaps::new(&table);
            for _ in 0..60 {
                let rows = f32x8::u_load(&random_rows(&mut rng, &table), 0);
                let x0 = rng.below(w as u32 - 7) as i32;
                let y = rng.below(h as u32) as i32;
                let shift = [rng.below(3) as i32 - 1, rng.below(3) as i32 - 1];
                let gather_with = |planes: &LightPlanes<'_>, columns: &TapColumns| {
                    let reads = LaneRows::of::<f32x8>(columns, rows);
                    let edge = TapOrigin {
                        x: x0,
                        y,
                        shift,
                        inside: false,
                    };
                    let inside = reads_inside(reads.extent, edge, 8, w as i32, h as i32);
                    let at = TapOrigin { inside, ..edge };
                    let mut per_lane = [f32x8::splat(0.0); 4];
                    let sums = &mut per_lane[..gathered];
                    gather_per_lane(planes, &table, columns, rows, &reads, at, sums);
                    // The first lane's row for every lane: the uniform gather.
                    let row = rows.to_array()[0];
                    let (taps, extent) = (light_taps.weighted(row), columns.extent[row as usize]);
                    let mut uniform = [f32x8::splat(0.0); 4];
                    gather_lanes(planes, taps, extent, edge, &mut uniform[..gathered]);
                    // Every lane against the reference gather (the per-pixel stage's) at its
                    // pixel, through its own row and through the first lane's.
                    let reference = |x: i32, row: u32| {
                        let at = TapOrigin {
                            x,
                            y,
                            shift,
                            inside: false,
                        };
                        gather(planes, light_taps.weighted(row), at)
                    };
                    let lanes = rows.to_array();
                    for (i, &r) in lanes.iter().enumerate() {
                        let x = x0 + i as i32;
                        let (own, first) = (reference(x, r), reference(x, lanes[0]));
                        for c in 0..gathered {
                            let why = format!("{kernel}, lane {i}, plane {c} of {gathered}");
                            let lane = |v: f32x8| v.to_array()[i].to_bits();
                            assert_eq!(lane(per_lane[c]), own[c].to_bits(), "per lane: {why}");
                            assert_eq!(lane(uniform[c]), first[c].to_bits(), "uniform: {why}");
                        }
                    }
                    let bits = |v: [f32x8; 4]| v.map(|p| p.to_array().map(f32::to_bits));
                    (bits(per_lane), bits(uniform))
                };
                let want = gather_with(&by_plane, &planar_columns);
                let got = gather_with(&by_pixel, &pixel_columns);
                assert_eq!(
                    got, want,
                    "{kernel}, {gathered} of {per_pixel} planes, at ({x0}, {y})"
                );
            }
            // Two chunks at once, inside the grid.
            let row = rng.below(table.rows());
            let (x0, y) = (12, 20);
            let pair = |planes: &LightPlanes<'_>, columns: &TapColumns| {
                let (mut a, mut b) = ([f32x8::splat(0.0); 4], [f32x8::splat(0.0); 4]);
                let (taps, extent) = (light_taps.weighted(row), columns.extent[row as usize]);
                let accs = [&mut a[..gathered], &mut b[..gathered]];
                let at = TapOrigin {
                    x: x0,
                    y,
                    shift: [1, -1],
                    inside: true,
                };
                gather_inside(planes, taps, extent, at, accs);
                [a, b].map(|v| v.map(|p| p.to_array().map(f32::to_bits)))
            };
            assert_eq!(
                pair(&by_pixel, &pixel_columns),
                pair(&by_plane, &planar_columns),
                "{kernel}, {gathered} of {per_pixel} planes, two chunks"
            );
        }
    }
}

#[test]
fn stored_pixels_land_where_the_interleaved_layout_puts_them() {
    for planes in 1..=4usize {
        let values: [f32x8; 4] =
            std::array::from_fn(|c| f32x8::new(std::array::from_fn(|i| (10 * c + i) as f32)));
        let mut data = vec![-1.0f32; 3 + 8 * planes + 2];
        store_pixels(&values[..planes], &mut data, 3);
        for i in 0..8 {
            for c in 0..planes {
                assert_eq!(
                    data[3 + i * planes + c],
                    (10 * c + i) as f32,
                    "{planes} planes"
                );
            }
        }
        assert_eq!(&data[..3], &[-1.0; 3]);
        assert_eq!(&data[3 + 8 * planes..], &[-1.0; 2]);
        // The one-lane store writes one pixel's planes.
        let mut one = vec![-1.0f32; planes];
        let scalar: Vec<f32> = (0..planes).map(|c| c as f32).collect();
        store_pixels(&scalar, &mut one, 0);
        assert_eq!(one, scalar);
    }
}

#[test]
fn a_row_run_reads_what_fetch_reads_on_either_side_of_the_grid() {
    // Narrower than, as wide as and wider than 8 lanes; runs wholly beyond, straddling and inside.
    for width in [3i32, 8, 13] {
        let (height, stride) = (3i32, width as usize + 5);
        let data: Vec<f32> = (0..stride * height as usize + 8)
            .map(|i| i as f32 + 0.5)
            .collect();
        for outside in [OUTSIDE, OUTSIDE_DEPTH] {
            let plane = Plane {
                data: &data,
                base: 2,
                row_stride: stride,
                pixel_step: 1,
                width,
                height,
                outside,
            };
            for y in -1..=height {
                for x in -10..=width + 1 {
                    let run = RowRun::at::<f32x8>(width, height, [stride, 1], x, y)
                        .read::<f32x8>(&plane)
                        .to_array();
                    let fetched: [f32; 8] = std::array::from_fn(|i| plane.fetch(x + i as i32, y));
                    assert_eq!(
                        run.map(f32::to_bits),
                        fetched.map(f32::to_bits),
                        "width {width}, ({x}, {y})"
                    );
                    let one =
                        RowRun::at::<f32>(width, height, [stride, 1], x, y).read::<f32>(&plane);
                    assert_eq!(
                        one.to_bits(),
                        fetched[0].to_bits(),
                        "1 lane, width {width}, ({x}, {y})"
                    );
                }
            }
        }
    }
}

#[test]
#[should_panic(expected = "outside the light buffer")]
fn a_per_lane_gather_claimed_interior_at_the_corner_panics_not_reads() {
    // `interior` claimed at pixel (0, 0) with a shift up and left: the one proof per call
    // must catch the reads before the buffer, not read them unchecked.
    let table = distance_table("ellipse2");
    let (w, h) = (64usize, 40usize);
    let row_stride = 4 * w;
    let data = vec![0.5f32; row_stride * h];
    let columns = TapColumns::new(&table, row_stride, 1, w);
    let planes = three_channels_and_depth(&data, w, h);
    let rows = f32x8::u_splat(table.rows() - 1);
    let reads = LaneRows::of::<f32x8>(&columns, rows);
    let mut acc = [f32x8::splat(0.0); 4];
    let shift = [-3, -3];
    let at = TapOrigin {
        x: 0,
        y: 0,
        shift,
        inside: true,
    };
    gather_per_lane(&planes, &table, &columns, rows, &reads, at, &mut acc);
}
