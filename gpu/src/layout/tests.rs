use std::mem::{offset_of, size_of};

use super::*;
use crate::shader::Program;

/// A struct's layout: name, size, and (member, offset) in declaration order.
type Layout = (&'static str, usize, Vec<(&'static str, usize)>);

/// The Rust side of `layout!(Type { field, … })`.
macro_rules! layout {
    ($t:ident { $($f:ident),* $(,)? }) => {
        (stringify!($t), size_of::<$t>(), vec![$((stringify!($f), offset_of!($t, $f))),*])
    };
}

/// Every struct shared with WGSL, with all its fields.
fn rust_layouts() -> Vec<Layout> {
    vec![
        layout!(LdiParams {
            items,
            width,
            height,
            pixels,
            stride,
            perspective,
            depth_origin,
            _pad0
        }),
        layout!(Triangle {
            v,
            bbox,
            depth_ref,
            depth_dx,
            depth_dy,
            mesh
        }),
        layout!(WorkItem { triangle, row }),
        layout!(SlabParams {
            slab,
            _pad0,
            _pad1,
            _pad2
        }),
        layout!(Globals {
            grid_w,
            grid_h,
            guard_left,
            width,
            height,
            slabs,
            lights,
            channels,
            jitter,
            slab_distance,
            flush_below,
            perlin4_scale,
            bg_r,
            bg_g,
            bg_b,
            row_len,
            guard_top,
            preintegration,
            planes,
            depth_planes,
            occlusion_eps,
            surface_holds,
            parity_meshes,
            inv_slab_distance,
            second_order_media,
            subpixel_shadows,
            back_to_front,
            projective,
            projective_centre,
            projective_depth_origin,
            projective_per_depth,
            depth_scaled,
            psi_at,
            psi_last,
            held_lit_side,
            horizon_at,
            hold_stride,
        }),
        layout!(Slab {
            front,
            back,
            jitter_hash
        }),
        layout!(LightHeader {
            taps,
            taps_per_phase,
            phase_count,
            level_of,
            level_top,
            level_phases,
            phase_bits,
            phase_mode,
            color,
            half_vector,
            to_light,
            fresnel,
            drift,
            spread,
            plain
        }),
        layout!(LightSlab {
            hash,
            phase,
            shift,
            residual
        }),
        layout!(Tap { dx, dy, w }),
        layout!(MaterialHeader {
            tf,
            tf_len,
            detail_kind,
            octave_count,
            octaves,
            inv_amplitude_sum,
            animated,
            time,
            texture,
            dims,
            has_texture,
            has_specular,
            spec_strength,
            spec_exponent,
            pre,
            spec_f0,
            lambert,
            bricks,
            pool,
        }),
        layout!(TransferEntry {
            color,
            alpha,
            attenuation
        }),
        layout!(Octave {
            frequency,
            amplitude
        }),
        layout!(MeshHeader {
            to_detail,
            material,
            subpixel
        }),
        layout!(Cursor { next, inside }),
        layout!(EyeParams {
            width,
            height,
            zoom,
            z_origin,
            axis,
            centre,
            turned_round,
            pixel_size,
            scale,
            _pad2
        }),
        layout!(PointParams {
            on,
            spot,
            pattern,
            pixel_size,
            center,
            color,
            axis,
            right,
            down,
            offset,
            depth,
            focal,
            frame_axis,
            inner,
            outer,
            pattern_size,
            pattern_centre,
            pattern_width,
            pattern_height,
            turned,
            _pad1,
            phase,
        }),
    ]
}

/// Every disagreement between the Rust layouts and the structs and bindings of `wgsl`.
fn mismatches(wgsl: &str, layouts: &[Layout], slots: &[(&str, u32)]) -> Vec<String> {
    let module = match naga::front::wgsl::parse_str(wgsl) {
        Ok(m) => m,
        Err(e) => return vec![format!("WGSL does not parse: {}", e.emit_to_string(wgsl))],
    };
    let mut out = Vec::new();
    for (name, size, fields) in layouts {
        let found = module.types.iter().find_map(|(_, ty)| match &ty.inner {
            naga::TypeInner::Struct { members, span } if ty.name.as_deref() == Some(name) => {
                Some((members, *span))
            }
            _ => None,
        });
        let Some((members, span)) = found else {
            out.push(format!("struct {name}: not in the WGSL"));
            continue;
        };
        if span as usize != *size {
            out.push(format!("struct {name}: WGSL size {span}, Rust size {size}"));
        }
        let wgsl_fields: Vec<(String, usize)> = members
            .iter()
            .map(|m| (m.name.clone().unwrap_or_default(), m.offset as usize))
            .collect();
        let rust_fields: Vec<(String, usize)> =
            fields.iter().map(|&(f, o)| (f.to_string(), o)).collect();
        if wgsl_fields != rust_fields {
            out.push(format!(
                "struct {name}: WGSL members {wgsl_fields:?}, Rust fields {rust_fields:?}"
            ));
        }
    }
    for &(name, slot) in slots {
        let binding = module
            .global_variables
            .iter()
            .find(|(_, g)| g.name.as_deref() == Some(name))
            .map(|(_, g)| g.binding.as_ref().map(|b| (b.group, b.binding)));
        if binding != Some(Some((0, slot))) {
            out.push(format!(
                "binding {name}: WGSL {binding:?}, Rust (0, {slot})"
            ));
        }
    }
    out
}

#[test]
fn rust_and_wgsl_layouts_agree() {
    for program in Program::ALL {
        let bad = mismatches(&program.source(), &rust_layouts(), slot::ALL);
        assert!(bad.is_empty(), "{} shader: {bad:#?}", program.name());
    }
}

#[test]
fn a_moved_field_is_reported() {
    let wgsl = Program::Sweep.source();
    // Swap two members of one struct on the WGSL side only.
    let moved = wgsl.replacen(
        "    depth_dx: f32,\n    depth_dy: f32,\n",
        "    depth_dy: f32,\n    depth_dx: f32,\n",
        1,
    );
    assert_ne!(moved, wgsl, "the test's pattern must match bindings.wgsl");
    let bad = mismatches(&moved, &rust_layouts(), slot::ALL);
    assert_eq!(bad.len(), 1, "{bad:#?}");
    assert!(bad[0].starts_with("struct Triangle:"), "{bad:#?}");
    // A member whose offset changes (an inserted field) is reported too.
    let grown = wgsl.replacen(
        "    jitter_hash: u32,\n",
        "    jitter_hash: u32,\n    extra: u32,\n",
        1,
    );
    let bad = mismatches(&grown, &rust_layouts(), slot::ALL);
    assert!(
        bad.iter()
            .any(|m| m.starts_with("struct Slab: WGSL size 16")),
        "{bad:#?}"
    );
    // And a binding moved on one side.
    let rebound = wgsl.replacen("@binding(22)", "@binding(29)", 1);
    let bad = mismatches(&rebound, &rust_layouts(), slot::ALL);
    assert!(
        bad.iter().any(|m| m.starts_with("binding taps:")),
        "{bad:#?}"
    );
}
