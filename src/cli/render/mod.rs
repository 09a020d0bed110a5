//! `convshadow render`: render a scene (or the embedded default scene) to PNG and/or EXR.
//!
//! This file runs the command in order: the scene and the arguments' overrides, the outputs
//! checked, then one render or a frame sequence under one progress bar, then the summary.
//! Beside it: `args.rs` (the arguments), `overrides.rs` (what they do to the scene),
//! `outputs.rs` (the output files, checked before any work), `reference.rs` (`--backend
//! reference`), `summary.rs` (outputs written, stats and the summary line).

mod args;
mod outputs;
mod overrides;
mod reference;
mod summary;

use std::io::IsTerminal;
use std::path::PathBuf;

use convshadow::pipeline::{Aov, RenderRequest, Rendered, check_light_index, render};
use convshadow_common::model::scene::{Scene, SlabSpec};

pub use args::RenderArgs;
use args::RenderBackend;
use outputs::output_paths;
use overrides::{apply_sweep_overrides, apply_view_overrides, frame_list, reference_samples};
use reference::render_reference;
use summary::{FrameStats, finish, finish_frames, save_output};

use super::frames;
use crate::cli::exit::{self, Failure};

/// Runs `convshadow render`.
pub fn run(args: &RenderArgs) -> Result<i32, Failure> {
    let mut scene = crate::cli::load_scene(args.scene.as_deref())?;
    crate::cli::override_size(&mut scene, args.width, args.height)?;
    apply_view_overrides(&mut scene, args)?;
    let (frame_list, time_step) = frame_list(args)?;
    apply_sweep_overrides(&mut scene, args)?;
    if let Some(list) = &frame_list {
        frames::check_times(&scene, list, time_step)?;
    }
    for aov in &args.aov {
        if let Aov::Light(l) = *aov {
            check_light_index(&scene, l)?;
        }
    }
    let outputs = output_paths(args, frame_list.as_deref(), &scene)?;
    let bar = progress_bar(args);
    // One bar over all frames: frame i's slab s is at i·slabs + s + 1.
    let frame_index = std::sync::atomic::AtomicU64::new(0);
    let frame_count = frame_list.as_ref().map_or(1, Vec::len) as u64;
    let slab_count = std::sync::atomic::AtomicU64::new(match scene.sweep.slabs {
        SlabSpec::Count(n) => u64::from(n),
        SlabSpec::Distance(_) | SlabSpec::Auto => 0,
    });
    let progress = |slab: u32| {
        if let Some(b) = &bar {
            use std::sync::atomic::Ordering::Relaxed;
            let per = slab_count.load(Relaxed);
            b.set_position(frame_index.load(Relaxed) * per + u64::from(slab) + 1);
        }
    };
    if let Some(b) = &bar {
        // The slab count is known once geometry is built; a count override is known now.
        if let SlabSpec::Count(n) = scene.sweep.slabs {
            b.set_length(u64::from(n) * frame_count);
        }
        if frame_count > 1 {
            b.set_style(
                indicatif::ProgressStyle::with_template(
                    "{spinner} {msg} slab {pos}/{len} {wide_bar} {eta}",
                )
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
            );
        }
    }
    let samples = reference_samples(args)?;
    let budget = convshadow::overrides::memory_budget(args.max_memory);
    let Some(backend) = args.backend.device() else {
        // The reference has no cancel point: a signal ends the run at once, before any output.
        exit::install_exit_on_signal(None);
        let r = render_reference(
            &scene,
            args.threads,
            samples,
            budget,
            args.allow_open,
            &args.aov,
        )?;
        return finish(&scene, args, &outputs, &r, bar.as_ref(), samples);
    };
    let request = RenderRequest {
        backend,
        threads: args.threads,
        path: args.path,
        skip_quiet: !args.no_skip_quiet,
        memory_budget: budget,
        allow_open: args.allow_open,
        progress: &progress,
        // SIGINT/SIGTERM raise it: the sweep stops and nothing is written (exit code 130).
        cancel: Some(exit::install_interrupt_handler()),
        every_slab: false,
        aovs: args.aov.clone(),
    };
    let Some(list) = frame_list else {
        let r = render(&scene, &request)?;
        if let Some(note) = &r.backend_note {
            convshadow::errln!("note: {}", crate::cli::exit::escape_line(note));
        }
        return finish(&scene, args, &outputs, &r, bar.as_ref(), 0);
    };
    let sequence = Sequence {
        scene: &scene,
        request: &request,
        outputs: &outputs,
        bar: bar.as_ref(),
        frame_index: &frame_index,
        slab_count: &slab_count,
        time_step,
    };
    let (r, done) = sequence.render(&list)?;
    finish_frames(&scene, args, &r, bar.as_ref(), &done, time_step)
}

/// The slab progress bar on a terminal (none when quiet, redirected, or for the reference).
fn progress_bar(args: &RenderArgs) -> Option<indicatif::ProgressBar> {
    // The reference has no per-slab progress to show.
    if !args.quiet && std::io::stderr().is_terminal() && args.backend != RenderBackend::Reference {
        let b = indicatif::ProgressBar::new(0);
        b.set_style(
            indicatif::ProgressStyle::with_template("{spinner} slab {pos}/{len} {wide_bar} {eta}")
                .unwrap_or_else(|_| indicatif::ProgressStyle::default_bar()),
        );
        Some(b)
    } else {
        None
    }
}

/// A frame sequence being rendered under one progress bar.
struct Sequence<'a> {
    scene: &'a Scene,
    request: &'a RenderRequest<'a>,
    outputs: &'a [PathBuf],
    bar: Option<&'a indicatif::ProgressBar>,
    frame_index: &'a std::sync::atomic::AtomicU64,
    slab_count: &'a std::sync::atomic::AtomicU64,
    time_step: f64,
}

impl Sequence<'_> {
    /// Renders and writes every frame of `list`; returns the last render and each frame's numbers.
    fn render(&self, list: &[u32]) -> Result<(Rendered, Vec<FrameStats>), Failure> {
        let (scene, request, outputs, bar) = (self.scene, self.request, self.outputs, self.bar);
        let (frame_index, slab_count, time_step) =
            (self.frame_index, self.slab_count, self.time_step);
        let frame_count = list.len() as u64;
        let mut done: Vec<FrameStats> = Vec::new();
        // Every complete output file so far, for the message if a signal stops the sequence.
        let mut written: Vec<PathBuf> = Vec::new();
        let mut last = None;
        for (i, &k) in list.iter().enumerate() {
            use std::sync::atomic::Ordering::Relaxed;
            frame_index.store(i as u64, Relaxed);
            if let Some(b) = &bar {
                b.set_message(format!("frame {}/{}", i + 1, list.len()));
            }
            let frame_scene = frames::scene_at_frame(scene, k, time_step);
            let r = render(&frame_scene, request).map_err(|e| {
                let f = Failure::from(e);
                if f.code == exit::INTERRUPTED {
                    exit::interrupted_after(&written)
                } else {
                    f
                }
            })?;
            if i == 0 {
                if let Some(note) = &r.backend_note {
                    convshadow::errln!("note: {}", crate::cli::exit::escape_line(note));
                }
                slab_count.store(u64::from(r.plan.slabs), Relaxed);
                if let Some(b) = &bar {
                    b.set_length(u64::from(r.plan.slabs) * frame_count);
                }
            }
            let paths: Vec<PathBuf> = outputs.iter().map(|p| frames::frame_path(p, k)).collect();
            for p in &paths {
                exit::check_interrupt_after(&written)?;
                save_output(scene, &r, p)?;
                written.push(p.clone());
            }
            done.push(FrameStats {
                frame: k,
                time: frames::frame_time(scene, k, time_step),
                image_hash: r.image_hash,
                ldi_hash: r.ldi_hash,
                seconds_total: r.seconds_total,
                outputs: paths,
            });
            last = Some(r);
        }
        exit::check_interrupt_after(&written)?;
        let r = last.expect("a parsed frame list is not empty");
        Ok((r, done))
    }
}
