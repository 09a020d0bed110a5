//! The GPU sweep's host-side checks: its tables, limits and bindings.

use super::*;
use crate::shader::Program;
use convshadow_common::contract::files::{GeometryFiles, PlanFiles};
use convshadow_common::model::scene::{Penumbra, Scene, SlabSpec};
use convshadow_common::prepare::geometry::SceneGeometry;

/// The default scene, small, with the distance penumbra and `kernel`: its geometry and plan.
fn distance_plan(kernel: &str) -> (SceneGeometry, RenderPlan) {
    let mut scene = Scene::default_scene();
    scene.image.width = 16;
    scene.image.height = 16;
    scene.sweep.slabs = SlabSpec::Count(40);
    scene.sweep.kernel = kernel.parse().expect("kernel");
    scene.sweep.penumbra = Penumbra::Distance;
    scene.revalidate().expect("scene");
    let g = SceneGeometry::build(&scene, &GeometryFiles::default()).expect("geometry");
    let plan = RenderPlan::new(&scene, &g, &PlanFiles::default()).expect("plan");
    (g, plan)
}

#[test]
fn level_tables_are_uploaded_where_the_headers_say() {
    let (g, plan) = distance_plan("box");
    let t = build_tables(&plan, &g.raster).expect("tables");
    assert_eq!(t.globals.planes, plan.channels + 1);
    assert_eq!(t.globals.depth_planes, 1);
    for (l, light) in plan.lights.iter().enumerate() {
        let (h, table) = (&t.lights[l], &light.table);
        let at = |i: u32, n: usize| &t.level_table[i as usize..][..n];
        assert_eq!(at(h.level_of, 41), &table.level_of[..]);
        assert_eq!(h.level_top, 40);
        assert_eq!(
            at(h.level_phases, table.slab_phase.len()),
            &table.slab_phase[..]
        );
        // 40 slabs: levels 1..=31 of one distance, then 32..=39 in pairs, 40 alone.
        assert_eq!(table.levels, 31 + 4 + 1);
        assert_eq!(table.slab_phase.len(), 36 * 40);
        // Every level's rows, as the table holds them.
        let n = (table.levels * table.phase_count * table.taps_per_phase) as usize;
        let uploaded = &t.taps[h.taps as usize..][..n];
        for (a, b) in uploaded.iter().zip(&table.taps) {
            assert_eq!((a.dx, a.dy, a.w), (b.dx, b.dy, b.w));
        }
        assert_eq!(h.phase_count, table.phase_count);
    }
}

#[test]
fn a_malformed_level_table_is_refused_naming_the_light() {
    let (g, mut plan) = distance_plan("ellipse2");
    let levels = plan.lights[1].table.levels;
    plan.lights[1].table.level_of[7] = levels;
    let err = build_tables(&plan, &g.raster).err().expect("refused");
    let msg = err.to_string();
    assert!(
        msg.contains("light 1") && msg.contains(&format!("level {levels} of {levels}")),
        "{msg}"
    );
    let (g, mut plan) = distance_plan("gaussian:7");
    plan.lights[0].table.slab_phase.pop();
    let msg = build_tables(&plan, &g.raster)
        .err()
        .expect("refused")
        .to_string();
    assert!(msg.contains("light 0") && msg.contains("schedule"), "{msg}");
}

#[test]
fn the_sweep_binds_the_counted_storage_buffers() {
    let wgsl = Program::Sweep.source();
    let module = naga::front::wgsl::parse_str(&wgsl).expect("the sweep WGSL parses");
    let info = naga::valid::Validator::new(
        naga::valid::ValidationFlags::all(),
        naga::valid::Capabilities::all(),
    )
    .validate(&module)
    .expect("the sweep WGSL validates");
    let (index, _) = module
        .entry_points
        .iter()
        .enumerate()
        .find(|(_, e)| e.name == "sweep_slab")
        .expect("sweep_slab");
    let used = info.get_entry_point(index);
    let storage = module
        .global_variables
        .iter()
        .filter(|(h, g)| {
            matches!(g.space, naga::AddressSpace::Storage { .. }) && !used[*h].is_empty()
        })
        .count();
    assert_eq!(storage as u32, SWEEP_STORAGE_BUFFERS);
}
