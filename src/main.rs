//! The `convshadow` command line.

use clap::{Parser, Subcommand};
use convshadow::commands;
use convshadow::exit;

/// Iterative convolution shadows for closed meshes filled with volumetric detail.
#[derive(Parser, Debug)]
#[command(name = "convshadow", version, about)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Compare two images (EXR or PNG; A is the reference): errors, PSNR, FLIP, 8-bit sRGB
    /// differences, optional JSON and heat-map.
    Diff(commands::diff::DiffArgs),
    /// Build the layered depth image and report fragments, layers and mesh defects.
    Ldi(commands::ldi::LdiArgs),
    /// Render a scene (the embedded default scene without SCENE) to PNG and/or EXR.
    Render(commands::render::RenderArgs),
    /// Speed against error: render a grid of cases (kernels × slab counts × lights) and write
    /// report.csv, report.md and speed_vs_error.png.
    Report(commands::report::ReportArgs),
}

fn main() {
    let cli = match Cli::try_parse() {
        Ok(c) => c,
        Err(e) => {
            let code = if e.use_stderr() {
                exit::BAD_ARGUMENTS
            } else {
                exit::OK
            };
            let _ = e.print();
            std::process::exit(code);
        }
    };
    let result = match &cli.command {
        Command::Diff(a) => commands::diff::run(a),
        Command::Ldi(a) => commands::ldi::run(a),
        Command::Render(a) => commands::render::run(a),
        Command::Report(a) => commands::report::run(a),
    };
    match result {
        Ok(code) => std::process::exit(code),
        Err(f) => {
            eprintln!("error: {}", f.message);
            std::process::exit(f.code);
        }
    }
}
