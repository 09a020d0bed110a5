use super::*;

/// Floats of every kind: ordinary, ±0, ±∞, NaN, subnormal, huge; from a `mix32` counter.
fn floats(seed: u32) -> [f32; MAX_LANES] {
    let special = [
        0.0,
        -0.0,
        f32::INFINITY,
        -f32::INFINITY,
        f32::NAN,
        1e-40,
        3e9,
        -2.5,
    ];
    let mut out = [0.0f32; MAX_LANES];
    for (i, v) in out.iter_mut().enumerate() {
        let h = mix32(seed.wrapping_mul(8).wrapping_add(i as u32));
        *v = match h % 4 {
            0 => special[(h >> 8) as usize % special.len()],
            1 => f32::from_bits(h),
            _ => (h >> 8) as f32 / 65536.0 - 128.0,
        };
    }
    out
}

/// Each lane of `eight` has the bits of `one` on that lane's inputs.
/// NaNs agree with any NaN: which operand's payload an operation on two NaNs returns is
/// not fixed by IEEE 754, and the compiler may swap the operands of `+` and `*` (it does in
/// the AVX2 build). The pipeline never lets a NaN reach a pixel, so payloads are no part of
/// the bit contract.
fn agree(eight: f32x8, one: impl Fn(usize) -> f32, what: &str) {
    let e = eight.to_array();
    for (i, v) in e.iter().enumerate() {
        let o = one(i);
        if v.is_nan() && o.is_nan() {
            continue;
        }
        assert_eq!(v.to_bits(), o.to_bits(), "{what}, lane {i}");
    }
}

#[test]
fn eight_lanes_give_the_bits_of_one_lane() {
    for seed in 0..2000 {
        let (a, b) = (floats(seed), floats(seed + 7919));
        let (va, vb) = (f32x8::new(a), f32x8::new(b));
        agree(va + vb, |i| a[i] + b[i], "add");
        agree(va * vb, |i| a[i] * b[i], "mul");
        agree(va / vb, |i| a[i] / b[i], "div");
        agree(Lane::floor(va), |i| Lane::floor(a[i]), "floor");
        agree(Lane::abs(va), |i| Lane::abs(a[i]), "abs");
        let m = va.gt(vb);
        agree(
            <f32x8 as Lane>::select(m, va, vb),
            |i| if a[i] > b[i] { a[i] } else { b[i] },
            "gt",
        );
        let m = <f32x8 as Lane>::m_or(va.lt(vb), va.ne(vb));
        agree(
            <f32x8 as Lane>::select(m, va, vb),
            |i| {
                <f32 as Lane>::select(
                    <f32 as Lane>::m_or(a[i].lt(b[i]), a[i].ne(b[i])),
                    a[i],
                    b[i],
                )
            },
            "lt, ne, or",
        );
        let t = va.trunc_u32().to_array();
        for i in 0..MAX_LANES {
            assert_eq!(t[i], a[i].trunc_u32(), "trunc lane {i}");
        }
        let mut h = [0u32; MAX_LANES];
        f32x8::u_store(f32x8::u_mix32(f32x8::u_iota(seed)), &mut h);
        for (i, v) in h.iter().enumerate() {
            assert_eq!(
                *v,
                f32::u_mix32(f32::u_iota(seed + i as u32)),
                "mix32 lane {i}"
            );
        }
        let idx: [u32; MAX_LANES] = std::array::from_fn(|i| h[i] % 16);
        let data: Vec<f32> = (0..16).map(|k| floats(seed + k)[k as usize % 8]).collect();
        agree(
            f32x8::gather(&data, u32x8::new(idx)),
            |i| f32::gather(&data, idx[i]),
            "gather",
        );
    }
}

/// Unit-range floats, exact 0 and 1 one time in eight each (light values and weights).
fn unit(h: u32) -> f32 {
    match h % 8 {
        0 => 0.0,
        1 => 1.0,
        _ => (h >> 8) as f32 / 16_777_216.0,
    }
}

#[test]
fn shifted_lanes_take_their_neighbours_or_the_fill() {
    let v = f32x8::new(std::array::from_fn(|i| i as f32 + 0.25));
    for by in -9..=9 {
        let got = v.shift_lanes(by, -1.0).to_array();
        let want: [f32; 8] = std::array::from_fn(|i| {
            let from = i as i32 + by;
            if (0..8).contains(&from) {
                from as f32 + 0.25
            } else {
                -1.0
            }
        });
        assert_eq!(got, want, "by {by}");
        assert_eq!(
            2.5f32.shift_lanes(by, -1.0),
            if by == 0 { 2.5 } else { -1.0 }
        );
    }
}

#[test]
fn a_grid_fetch_reads_inside_and_gives_the_outside_value_beyond() {
    let (width, height, stride, base) = (13i32, 5i32, 53usize, 3usize);
    let data: Vec<f32> = (0..base + 4 * stride + 13 * 4)
        .map(|k| k as f32 + 0.5)
        .collect();
    // Planar rows (pixels 1 apart) and pixel-interleaved ones (pixels 4 apart).
    for (seed, step) in (0..2000u32).flat_map(|s| [(s, 1usize), (s, 4)]) {
        let h: [u32; MAX_LANES] = std::array::from_fn(|i| mix32(seed * 8 + i as u32));
        // Coordinates from −4 to width + 3 (and height + 3), and now and then far beyond.
        let coord = |v: u32, n: i32| match v % 16 {
            0 => i32::MIN + (v >> 8) as i32,
            1 => i32::MAX - (v >> 8) as i32,
            _ => (v >> 4) as i32 % (n + 8) - 4,
        };
        let x = h.map(|v| coord(v, width) as u32);
        let y = h.map(|v| coord(mix32(v), height) as u32);
        let grid = Grid {
            data: &data,
            base,
            stride,
            step,
            width,
            height,
        };
        let got = f32x8::fetch_grid(&grid, u32x8::new(x), u32x8::new(y), -1.0);
        agree(
            got,
            |i| {
                let (xi, yi) = (x[i] as i32, y[i] as i32);
                let inside = (0..width).contains(&xi) && (0..height).contains(&yi);
                let want = if inside {
                    data[base + yi as usize * stride + xi as usize * step]
                } else {
                    -1.0
                };
                let one = f32::fetch_grid(&grid, x[i], y[i], -1.0);
                assert_eq!(one.to_bits(), want.to_bits(), "one lane at ({xi}, {yi})");
                want
            },
            "fetch_grid",
        );
    }
}

/// [`Layout::pixel_order`], [`Layout::plane_order`], [`Layout::from_lane_pairs`] and
/// [`Layout::to_lane_pairs`] of `C` planes against their definitions, element by element.
fn check_orders<const C: usize>() {
    let planes: [f32x8; C] =
        std::array::from_fn(|c| f32x8::new(std::array::from_fn(|i| (10 * c + i) as f32)));
    let pixels = f32x8::pixel_order(planes);
    for (j, v) in pixels.iter().enumerate() {
        for (m, got) in v.to_array().into_iter().enumerate() {
            let (c, i) = ((8 * j + m) % C, (8 * j + m) / C);
            assert_eq!(got, (10 * c + i) as f32, "{C} planes: value {j} slot {m}");
        }
    }
    let back = f32x8::plane_order(pixels).map(|v| v.to_array());
    assert_eq!(back, planes.map(|v| v.to_array()), "{C} planes back");
    let pairs = f32x8::to_lane_pairs(&planes);
    for (k, v) in pairs.iter().enumerate() {
        for (s, got) in v.to_array().into_iter().enumerate() {
            let (lane, c) = (k + 4 * (s / 4), s % 4);
            let want = if c < C { (10 * c + lane) as f32 } else { 0.0 };
            assert_eq!(got, want, "{C} planes: value {k} slot {s}");
        }
    }
    let from = f32x8::from_lane_pairs::<C>(&pairs).map(|v| v.to_array());
    assert_eq!(
        from,
        planes.map(|v| v.to_array()),
        "{C} planes from lane pairs"
    );
    // One lane: plane order is pixel order, and lane 0's sums are its planes.
    let one: [f32; C] = std::array::from_fn(|c| c as f32 + 0.5);
    assert_eq!(f32::pixel_order(one), one);
    assert_eq!(f32::plane_order(one), one);
    assert_eq!(f32::from_lane_pairs::<C>(&f32::to_lane_pairs(&one)), one);
}

#[test]
fn orders_of_pixel_interleaved_planes_move_every_value_where_defined() {
    check_orders::<1>();
    check_orders::<2>();
    check_orders::<3>();
    check_orders::<4>();
}

#[test]
fn halves_hold_two_lanes_reads_and_each_halfs_weights_spread_over_it() {
    let data: Vec<f32> = (0..64u32).map(|k| unit(mix32(k ^ 0x77))).collect();
    for (a, b) in [(0usize, 60usize), (13, 2), (7, 7), (59, 31)] {
        // SAFETY: a + 4 and b + 4 are at most 64 = data.len().
        let got = unsafe { load_halves(data.as_ptr().add(a), data.as_ptr().add(b)) };
        let want: [f32; 8] = std::array::from_fn(|s| data[if s < 4 { a + s } else { b + s - 4 }]);
        assert_eq!(got.to_array(), want, "reads at {a} and {b}");
    }
    let (wa, wb) = ([0.5f32, 0.25, 0.125, 0.0625], [1.0f32, 2.0, 3.0, 4.0]);
    let both = halves(&wa, &wb);
    assert_eq!(
        both.to_array(),
        [0.5, 0.25, 0.125, 0.0625, 1.0, 2.0, 3.0, 4.0]
    );
    for (k, spread) in splat_within_halves(both).iter().enumerate() {
        let want: [f32; 8] = std::array::from_fn(|s| if s < 4 { wa[k] } else { wb[k] });
        assert_eq!(spread.to_array(), want, "corner {k}");
    }
}

#[test]
fn eight_lane_gathers_and_blocks_give_the_bits_of_one_lane() {
    let data: Vec<f32> = (0..4096u32).map(|k| unit(mix32(k ^ 0x5151))).collect();
    let table: Vec<[f32; 4]> = (0..64u32)
        .map(|k| std::array::from_fn(|j| unit(mix32(k * 4 + j as u32))))
        .collect();
    let ints: Vec<u32> = (0..64u32).map(|k| mix32(k + 99)).collect();
    let stride = 61;
    for seed in 0..500u32 {
        let h: [u32; MAX_LANES] = std::array::from_fn(|i| mix32(seed * 8 + i as u32));
        let phase = u32x8::new(h.map(|v| v % 64));
        let ph = phase.to_array();
        agree(
            f32x8::gather(&data, u32x8::new(h.map(|v| v % 4096))),
            |i| f32::gather(&data, h[i] % 4096),
            "gather",
        );
        let mut out = [0u32; MAX_LANES];
        f32x8::u_store(f32x8::u_gather(&ints, phase), &mut out);
        for i in 0..MAX_LANES {
            assert_eq!(out[i], f32::u_gather(&ints, ph[i]), "u_gather lane {i}");
        }
        // SAFETY: every index is below 64 = ints.len().
        f32x8::u_store(unsafe { f32x8::u_gather_unchecked(&ints, phase) }, &mut out);
        for i in 0..MAX_LANES {
            // SAFETY: as above.
            let one = unsafe { f32::u_gather_unchecked(&ints, ph[i]) };
            assert_eq!((out[i], one), (ints[ph[i] as usize], ints[ph[i] as usize]));
        }
        let at = (h[0] % 56) as usize;
        f32x8::u_store(f32x8::u_load(&ints, at), &mut out);
        for (i, v) in out.iter().enumerate() {
            assert_eq!(*v, f32::u_load(&ints, at + i), "u_load lane {i}");
        }
        let four = f32x8::gather4(&table, phase);
        for (j, v) in four.iter().enumerate() {
            agree(*v, |i| f32::gather4(&table, ph[i])[j], "gather4");
        }
        // Two taps into an accumulator that starts at arbitrary values; signed offsets.
        let origin = 2000;
        let start = f32x8::new(std::array::from_fn(|i| unit(h[i] >> 3)));
        let mut eight = f32x8::acc_from(start);
        let mut one: [f32; MAX_LANES] = start.to_array();
        for tap in 0..2u32 {
            let rel: [u32; MAX_LANES] =
                std::array::from_fn(|i| ((mix32(h[i] + tap) % 1500) as i32 - 750) as u32);
            let w8 = f32x8::weights4(&table, phase + u32x8::splat(0));
            let mut sums = [eight];
            f32x8::acc_blocks(&mut sums, &w8, &data, origin, 0, u32x8::new(rel), stride);
            // The unchecked blocks read the same values (every read here lies in `data`).
            let mut unchecked = [eight];
            // SAFETY: origin ± 750 plus stride + 1 lies in 0..4096.
            unsafe {
                f32x8::acc_blocks_unchecked(
                    &mut unchecked,
                    &w8,
                    &data,
                    origin,
                    0,
                    u32x8::new(rel),
                    stride,
                );
            }
            agree(
                f32x8::acc_finish(unchecked[0]),
                |i| f32x8::acc_finish(sums[0]).to_array()[i],
                "acc_blocks_unchecked",
            );
            eight = sums[0];
            for i in 0..MAX_LANES {
                let w1 = f32::weights4(&table, ph[i]);
                let mut s1 = [one[i]];
                f32::acc_blocks(&mut s1, &w1, &data, origin, 0, rel[i], stride);
                let mut u1 = [one[i]];
                // SAFETY: as above.
                unsafe {
                    f32::acc_blocks_unchecked(&mut u1, &w1, &data, origin, 0, rel[i], stride);
                }
                assert_eq!(
                    u1[0].to_bits(),
                    s1[0].to_bits(),
                    "one-lane unchecked blocks"
                );
                one[i] = s1[0];
            }
        }
        agree(f32x8::acc_finish(eight), |i| one[i], "acc_blocks");
    }
}

#[test]
fn the_largest_lane_and_a_uniform_value_are_those_of_the_lanes() {
    for seed in 0..300u32 {
        // Small values, so that equal lanes are common; some chunks all equal.
        let h: [u32; MAX_LANES] = std::array::from_fn(|i| mix32(seed * 8 + i as u32) % 3);
        let lanes = if seed % 4 == 0 { [h[0]; MAX_LANES] } else { h };
        let lanes = lanes.map(|v| v.wrapping_mul(0x8000_0001));
        let v = u32x8::new(lanes);
        assert_eq!(f32x8::u_largest(v), *lanes.iter().max().unwrap());
        let same = lanes.iter().all(|&x| x == lanes[0]);
        assert_eq!(f32x8::u_uniform(v), same.then_some(lanes[0]), "{lanes:?}");
        assert_eq!(
            (f32::u_largest(lanes[3]), f32::u_uniform(lanes[3])),
            (lanes[3], Some(lanes[3]))
        );
    }
    // Full-range values, the largest in each lane in turn (the reduction visits every lane).
    for at in 0..8 {
        for seed in 0..50u32 {
            let mut lanes: [u32; 8] = std::array::from_fn(|i| mix32(seed * 8 + i as u32) >> 1);
            lanes[at] = u32::MAX - seed;
            assert_eq!(
                f32x8::u_largest(u32x8::new(lanes)),
                u32::MAX - seed,
                "{lanes:?}"
            );
        }
    }
}

#[test]
#[should_panic(expected = "outside")]
fn a_block_outside_the_data_panics() {
    let data = vec![1.0f32; 100];
    let w = f32x8::weights4(&[[0.25; 4]], u32x8::splat(0));
    let rel = u32x8::new([0, 1, 2, 3, 4, 5, 6, 90]);
    // Lane 7's bottom-right corner is 90 + 10 + 1 = 101.
    let mut sums = [f32x8::acc_from(f32x8::splat(0.0))];
    f32x8::acc_blocks(&mut sums, &w, &data, 0, 0, rel, 10);
}
